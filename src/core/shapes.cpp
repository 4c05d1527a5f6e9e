#include "core/shapes.h"

#include <cmath>
#include <numbers>

namespace lod::shapes {

namespace {

constexpr float two_pi = 2.0f * std::numbers::pi_v<float>;

float3 normalized(float3 v) {
  float len = std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
  return {v.x / len, v.y / len, v.z / len};
}

// cos/sin of 2*pi*i/n, with i == n mapped to i == 0 so seam copies get bit-identical positions.
void unit_circle(uint32_t i, uint32_t n, float& c, float& s) {
  float a = two_pi * float(i % n) / float(n);
  c = std::cos(a);
  s = std::sin(a);
}

void add_quad(Mesh& m, uint32_t a, uint32_t b, uint32_t c, uint32_t d) {
  m.indices.insert(m.indices.end(), {a, b, c, a, c, d});
}

}  // namespace

Mesh icosphere(uint32_t subdivisions) {
  const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
  Mesh m;
  const float3 corners[12] = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                              {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (const float3& c : corners) m.positions.push_back(normalized(c));
  m.indices = {0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4, 11, 10, 2, 10, 7, 6, 7, 1, 8,
               3, 9, 4, 3, 4, 2, 3, 2, 6, 3, 6, 8, 3, 8, 9, 4, 9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7, 9, 8, 1};
  for (uint32_t level = 0; level < subdivisions; ++level) {
    m = subdivide_midpoint(m);
    for (float3& p : m.positions) p = normalized(p);
  }
  m.normals = m.positions;
  return m;
}

Mesh torus(float major_radius, float minor_radius, uint32_t segments, uint32_t sides) {
  Mesh m;
  m.uvs[0].reserve(size_t(segments + 1) * (sides + 1));
  for (uint32_t i = 0; i <= segments; ++i) {
    float cu, su;
    unit_circle(i, segments, cu, su);
    for (uint32_t j = 0; j <= sides; ++j) {
      float cv, sv;
      unit_circle(j, sides, cv, sv);
      float ring = major_radius + minor_radius * cv;
      m.positions.push_back({ring * cu, ring * su, minor_radius * sv});
      m.normals.push_back({cv * cu, cv * su, sv});
      m.uvs[0].push_back({float(i) / float(segments), float(j) / float(sides)});
    }
  }
  auto at = [&](uint32_t i, uint32_t j) { return i * (sides + 1) + j; };
  for (uint32_t i = 0; i < segments; ++i)
    for (uint32_t j = 0; j < sides; ++j) add_quad(m, at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
  return m;
}

Mesh grid(uint32_t nx, uint32_t ny) {
  Mesh m;
  for (uint32_t j = 0; j <= ny; ++j)
    for (uint32_t i = 0; i <= nx; ++i) {
      float x = float(i) / float(nx), y = float(j) / float(ny);
      m.positions.push_back({x, y, 0});
      m.normals.push_back({0, 0, 1});
      m.uvs[0].push_back({x, y});
    }
  auto at = [&](uint32_t i, uint32_t j) { return j * (nx + 1) + i; };
  for (uint32_t j = 0; j < ny; ++j)
    for (uint32_t i = 0; i < nx; ++i) add_quad(m, at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
  return m;
}

Mesh cube() {
  // Each face: outward normal n and in-plane axes u, v with u x v = n, so corners listed
  // -u-v, +u-v, +u+v, -u+v run counter-clockwise seen from outside.
  struct Face {
    float3 n, u, v;
  };
  const Face faces[6] = {{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}},  {{-1, 0, 0}, {0, 0, 1}, {0, 1, 0}},
                         {{0, 1, 0}, {0, 0, 1}, {1, 0, 0}},  {{0, -1, 0}, {1, 0, 0}, {0, 0, 1}},
                         {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}},  {{0, 0, -1}, {0, 1, 0}, {1, 0, 0}}};
  const float su[4] = {-1, 1, 1, -1}, sv[4] = {-1, -1, 1, 1};
  Mesh m;
  for (const Face& f : faces) {
    uint32_t base = uint32_t(m.positions.size());
    for (int k = 0; k < 4; ++k) {
      m.positions.push_back({f.n.x + su[k] * f.u.x + sv[k] * f.v.x, f.n.y + su[k] * f.u.y + sv[k] * f.v.y,
                             f.n.z + su[k] * f.u.z + sv[k] * f.v.z});
      m.normals.push_back(f.n);
      m.uvs[0].push_back({(su[k] + 1) / 2, (sv[k] + 1) / 2});
    }
    add_quad(m, base, base + 1, base + 2, base + 3);
  }
  return m;
}

Mesh cylinder(uint32_t segments, float height) {
  Mesh m;
  const float z0 = -height / 2, z1 = height / 2;
  // Side: two rings with a duplicated seam column so uvs run 0..1 without wrapping.
  for (uint32_t i = 0; i <= segments; ++i) {
    float c, s;
    unit_circle(i, segments, c, s);
    for (float z : {z0, z1}) {
      m.positions.push_back({c, s, z});
      m.normals.push_back({c, s, 0});
      m.uvs[0].push_back({float(i) / float(segments), z == z0 ? 0.0f : 1.0f});
    }
  }
  for (uint32_t i = 0; i < segments; ++i) add_quad(m, 2 * i, 2 * (i + 1), 2 * (i + 1) + 1, 2 * i + 1);
  // Caps: own vertices (hard edge), planar uvs; the rim positions equal the side's bit for bit.
  for (int cap = 0; cap < 2; ++cap) {
    float z = cap ? z1 : z0, nz = cap ? 1.0f : -1.0f;
    uint32_t center = uint32_t(m.positions.size());
    m.positions.push_back({0, 0, z});
    m.normals.push_back({0, 0, nz});
    m.uvs[0].push_back({0.5f, 0.5f});
    for (uint32_t i = 0; i < segments; ++i) {
      float c, s;
      unit_circle(i, segments, c, s);
      m.positions.push_back({c, s, z});
      m.normals.push_back({0, 0, nz});
      m.uvs[0].push_back({0.5f + 0.5f * c, 0.5f + 0.5f * s});
    }
    for (uint32_t i = 0; i < segments; ++i) {
      uint32_t a = center + 1 + i, b = center + 1 + (i + 1) % segments;
      if (cap) m.indices.insert(m.indices.end(), {center, a, b});
      else m.indices.insert(m.indices.end(), {center, b, a});
    }
  }
  return m;
}

Mesh fin() {
  Mesh m;
  const float h = std::sqrt(3.0f) / 2.0f;
  m.positions = {{0, 0, 0}, {0, 0, 1}, {1, 0, 0.5f}, {-0.5f, h, 0.5f}, {-0.5f, -h, 0.5f}};
  m.indices = {0, 1, 2, 0, 1, 3, 0, 1, 4};
  return m;
}

}  // namespace lod::shapes
