// Cameras: named view directions, fitting a bounding sphere, turntables, and the matrices. The
// projection is the one the LOD runtime's screen-space error assumes: vertical field of view, so an
// object-space length e at depth d covers e * H / (2 d tan(fov / 2)) pixels.
#include <cmath>
#include <string>

#include "lodkit/error.h"
#include "render/internal.h"

namespace lod {

namespace {

struct Named {
  const char* name;
  float3 direction;
};
constexpr Named named_views[] = {
    {"front", {0, 0, 1}},           {"back", {0, 0, -1}},          {"right", {1, 0, 0}},
    {"left", {-1, 0, 0}},           {"top", {0, 1, 0}},            {"bottom", {0, -1, 0}},
    {"iso", {1, 1, 1}},             {"iso-front-right", {1, 1, 1}}, {"iso-front-left", {-1, 1, 1}},
    {"iso-back-right", {1, 1, -1}}, {"iso-back-left", {-1, 1, -1}}, {"iso-front-right-below", {1, -1, 1}},
    {"iso-front-left-below", {-1, -1, 1}}, {"iso-back-right-below", {1, -1, -1}}, {"iso-back-left-below", {-1, -1, -1}},
};

double length(const float3& v) { return std::sqrt(double(v.x) * v.x + double(v.y) * v.y + double(v.z) * v.z); }

struct Basis {
  double right[3], up[3], back[3];  // eye-space x, y, z in object space (the eye looks down -back)
};

Basis camera_basis(const RenderCamera& c) {
  Basis b;
  double z[3] = {double(c.eye.x) - c.target.x, double(c.eye.y) - c.target.y, double(c.eye.z) - c.target.z};
  const double zl = std::sqrt(z[0] * z[0] + z[1] * z[1] + z[2] * z[2]);
  for (double& v : z) v /= zl;
  const double u[3] = {c.up.x, c.up.y, c.up.z};
  double x[3] = {u[1] * z[2] - u[2] * z[1], u[2] * z[0] - u[0] * z[2], u[0] * z[1] - u[1] * z[0]};
  const double xl = std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
  for (double& v : x) v /= xl;
  const double y[3] = {z[1] * x[2] - z[2] * x[1], z[2] * x[0] - z[0] * x[2], z[0] * x[1] - z[1] * x[0]};
  for (int k = 0; k < 3; ++k) b.right[k] = x[k], b.up[k] = y[k], b.back[k] = z[k];
  return b;
}

// Up for a view direction: +y, unless the view is (nearly) along y.
float3 up_for(const float3& direction) {
  const double l = length(direction);
  if (std::abs(direction.y) > 0.999 * l) return direction.y > 0 ? float3{0, 0, -1} : float3{0, 0, 1};
  return {0, 1, 0};
}

RenderCamera fit(const BoundingSphere& sphere, const float3& direction, double aspect, double fov, bool orthographic) {
  if (!(aspect > 0) || !std::isfinite(aspect)) throw_usage("camera: the image aspect must be positive");
  if (!orthographic && !(fov > 0 && fov < M_PI)) throw_usage("camera: the field of view must be in (0, 180) degrees");
  const double l = length(direction);
  if (!(l > 0) || !std::isfinite(l)) throw_usage("camera: the view direction must be a non-zero vector");
  const double radius = sphere.radius > 0 ? sphere.radius : 1.0;
  RenderCamera c;
  c.target = sphere.center;
  c.up = up_for(direction);
  c.fov = fov;
  double distance;
  if (orthographic) {
    // The diameter across the smaller side of the image; the eye stands off by two radii.
    c.ortho_height = 2 * radius / std::min(1.0, aspect);
    distance = 2 * radius;
  } else {
    // The sphere touches the narrower of the two fields of view.
    const double half_vertical = fov / 2;
    const double half_horizontal = std::atan(std::tan(half_vertical) * aspect);
    distance = radius / std::sin(std::min(half_vertical, half_horizontal));
  }
  c.eye = {float(sphere.center.x + direction.x / l * distance), float(sphere.center.y + direction.y / l * distance),
           float(sphere.center.z + direction.z / l * distance)};
  // A little slack so the front and back of the sphere are never clipped.
  c.near = std::max(distance - radius * 1.01, distance * 1e-3);
  c.far = distance + radius * 1.01;
  return c;
}

}  // namespace

float3 view_direction(const std::string& name) {
  for (const Named& view : named_views)
    if (name == view.name) return view.direction;
  // "x,y,z"
  float3 v;
  char tail = 0;
  if (std::sscanf(name.c_str(), "%f,%f,%f%c", &v.x, &v.y, &v.z, &tail) == 3 && std::isfinite(v.x) &&
      std::isfinite(v.y) && std::isfinite(v.z) && length(v) > 0)
    return v;
  std::string names;
  for (const Named& view : named_views) names += std::string(names.empty() ? "" : ", ") + view.name;
  throw_usage("unknown view '" + name + "': use " + names + ", or a direction x,y,z");
}

std::vector<std::string> view_names() {
  std::vector<std::string> names;
  for (const Named& view : named_views) names.push_back(view.name);
  return names;
}

RenderCamera fit_camera(const BoundingSphere& sphere, float3 direction, double aspect, double fov, bool orthographic) {
  return fit(sphere, direction, aspect, fov, orthographic);
}

RenderCamera turntable_camera(const BoundingSphere& sphere, uint32_t frame, uint32_t frames, double aspect,
                              double elevation, double fov) {
  if (frames == 0 || frame >= frames) throw_usage("turntable: frame " + std::to_string(frame) + " of " + std::to_string(frames));
  if (!(std::abs(elevation) < M_PI / 2)) throw_usage("turntable: the elevation must be within (-90, 90) degrees");
  const double angle = 2 * M_PI * frame / frames;
  const float3 direction{float(std::sin(angle) * std::cos(elevation)), float(std::sin(elevation)),
                         float(std::cos(angle) * std::cos(elevation))};
  RenderCamera c = fit(sphere, direction, aspect, fov, false);
  c.up = {0, 1, 0};  // the turntable's axis, even when looking steeply down
  return c;
}

std::vector<float3> sphere_directions(uint32_t count) {
  std::vector<float3> directions;
  const double golden = M_PI * (3 - std::sqrt(5.0));
  for (uint32_t i = 0; i < count; ++i) {
    const double y = 1 - (i + 0.5) * 2 / count;
    const double r = std::sqrt(std::max(0.0, 1 - y * y));
    const double a = golden * i;
    directions.push_back({float(r * std::sin(a)), float(y), float(r * std::cos(a))});
  }
  return directions;
}

namespace detail {

void check_camera(const RenderCamera& c) {
  const float3 view{c.eye.x - c.target.x, c.eye.y - c.target.y, c.eye.z - c.target.z};
  const double l = length(view);
  if (!(l > 0) || !std::isfinite(l)) throw_usage("camera: the eye and the target must be distinct finite points");
  const double ul = length(c.up);
  const double cross = length({c.up.y * view.z - c.up.z * view.y, c.up.z * view.x - c.up.x * view.z,
                               c.up.x * view.y - c.up.y * view.x});
  if (!(ul > 0) || !(cross > 1e-6 * ul * l)) throw_usage("camera: the up direction must not be parallel to the view");
  if (!(c.near > 0) || !(c.far > c.near) || !std::isfinite(c.far)) throw_usage("camera: need 0 < near < far");
  if (c.ortho_height > 0) {
    if (!std::isfinite(c.ortho_height)) throw_usage("camera: the orthographic height must be finite");
  } else if (!(c.fov > 0 && c.fov < M_PI)) {
    throw_usage("camera: the field of view must be in (0, 180) degrees");
  }
}

Mat4 view_matrix(const RenderCamera& c) {
  const Basis b = camera_basis(c);
  const double e[3] = {c.eye.x, c.eye.y, c.eye.z};
  Mat4 m{};
  for (int k = 0; k < 3; ++k) {
    m[k * 4 + 0] = b.right[k];
    m[k * 4 + 1] = b.up[k];
    m[k * 4 + 2] = b.back[k];
  }
  m[12] = -(b.right[0] * e[0] + b.right[1] * e[1] + b.right[2] * e[2]);
  m[13] = -(b.up[0] * e[0] + b.up[1] * e[1] + b.up[2] * e[2]);
  m[14] = -(b.back[0] * e[0] + b.back[1] * e[1] + b.back[2] * e[2]);
  m[15] = 1;
  return m;
}

Mat4 projection_matrix(const RenderCamera& c, double aspect) {
  const double n = c.near, f = c.far;
  Mat4 m{};
  if (c.ortho_height > 0) {
    m[0] = 2 / (c.ortho_height * aspect);
    m[5] = 2 / c.ortho_height;
    // Reversed: depth (f - d) / (f - n) for a point d in front of the eye.
    m[10] = 1 / (f - n);
    m[14] = f / (f - n);
    m[15] = 1;
  } else {
    const double t = 1 / std::tan(c.fov / 2);
    m[0] = t / aspect;
    m[5] = t;
    // Reversed: depth n (f - d) / ((f - n) d).
    m[10] = n / (f - n);
    m[11] = -1;
    m[14] = n * f / (f - n);
  }
  return m;
}

double eye_depth(const RenderCamera& c, double window_depth) {
  const double n = c.near, f = c.far;
  if (c.ortho_height > 0) return f - window_depth * (f - n);
  return n * f / (n + window_depth * (f - n));
}

}  // namespace detail

float3 project(const RenderCamera& camera, uint32_t width, uint32_t height, const float3& point) {
  detail::check_camera(camera);
  const detail::Mat4 v = detail::view_matrix(camera);
  const detail::Mat4 p = detail::projection_matrix(camera, double(width) / height);
  const double in[4] = {point.x, point.y, point.z, 1};
  double eye[4] = {}, clip[4] = {};
  for (int r = 0; r < 4; ++r)
    for (int k = 0; k < 4; ++k) eye[r] += v[k * 4 + r] * in[k];
  for (int r = 0; r < 4; ++r)
    for (int k = 0; k < 4; ++k) clip[r] += p[k * 4 + r] * eye[k];
  const double x = clip[0] / clip[3], y = clip[1] / clip[3];
  return {float((x + 1) / 2 * width), float((1 - y) / 2 * height), float(-eye[2])};
}

}  // namespace lod
