// Wavefront MTL material libraries, as OBJ files name them (mtllib): what each material looks like,
// mapped to glTF's metallic-roughness core as gltfpack and obj2gltf map it. Statements lodkit has
// no place for (Ka, Ks, illum, map_Ks, ...) are skipped; a malformed number in one it reads is bad
// input, naming the file and line.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>

#include "io/text_reader.h"
#include "lodkit/io.h"

namespace lod {

namespace {

// Reads up to three numbers, clamped to [0, 1] as glTF's factors are; one given stands for all
// three (MTL allows `Kd 0.5`).
float3 read_rgb(io::TextReader& in, const char* what) {
  float c[3];
  c[0] = in.read_float(what);
  if (!in.try_read_float(c[1])) c[1] = c[2] = c[0];
  else c[2] = in.read_float(what);
  for (float& x : c) x = std::clamp(x, 0.0f, 1.0f);
  return {c[0], c[1], c[2]};
}

// A texture statement's file: its options (-bm 1, -s 1 1 1, -clamp on, ...) skipped, the rest of the
// line the path (names may hold spaces); '\' separators as '/'; relative to `folder`.
std::string texture_path(io::TextReader& in, const std::filesystem::path& folder) {
  // Options and how many values each takes at most (values are numbers, or on/off).
  static const std::pair<std::string_view, int> options[] = {
      {"-blendu", 1}, {"-blendv", 1}, {"-bm", 1}, {"-boost", 1}, {"-cc", 1}, {"-clamp", 1}, {"-imfchan", 1},
      {"-mm", 2}, {"-o", 3}, {"-s", 3}, {"-t", 3}, {"-texres", 1}, {"-type", 1}};
  for (;;) {
    const std::string_view option = in.peek_token();
    const auto known = std::find_if(std::begin(options), std::end(options), [&](const auto& o) { return o.first == option; });
    if (known == std::end(options)) break;
    in.token();
    for (int k = 0; k < known->second; ++k) {
      const std::string_view value = in.peek_token();
      float number;
      const bool word = value == "on" || value == "off" || (option == "-imfchan" || option == "-type");
      if (value.empty() || (!word && !io::parse_float(value, number))) break;
      in.token();
    }
  }
  std::string file(in.rest_of_line());
  if (file.empty()) in.fail("a texture statement names no file");
  std::replace(file.begin(), file.end(), '\\', '/');
  const std::filesystem::path path = std::filesystem::path(file);
  return (path.is_absolute() ? path : (folder / path).lexically_normal()).string();
}

void append_values(std::string& out, const char* key, std::initializer_list<float> values) {
  out += key;
  for (float v : values) out += ' ', io::append_float(out, v);
  out += '\n';
}

}  // namespace

void write_mtl(const Mesh& mesh, std::string& out, const std::filesystem::path& folder) {
  out += "# written by lodkit\n";
  const std::vector<bool> used = used_materials(mesh, mesh.material_looks.size());
  const std::vector<uint32_t> all_zero = {0};  // (no per-triangle ids: every triangle uses material 0)
  // The names usemtl gives the materials (write_obj).
  const std::map<uint32_t, std::string> names = io::obj_names(mesh.material_names, mesh.materials.empty() ? all_zero : mesh.materials);
  for (size_t id = 0; id < mesh.material_looks.size(); ++id) {
    if (!used[id]) continue;
    const std::string& name = names.at(uint32_t(id));
    const MaterialLook& look = mesh.material_looks[id];
    out += "\nnewmtl " + name + "\n";
    append_values(out, "Kd", {look.base_color.x, look.base_color.y, look.base_color.z});
    append_values(out, "d", {look.base_color.w});
    append_values(out, "Ke", {look.emissive.x, look.emissive.y, look.emissive.z});
    append_values(out, "Pm", {look.metallic});
    append_values(out, "Pr", {look.roughness});
    // For readers without Pr: the Phong exponent read_mtl maps to this roughness.
    const double r = std::max(double(look.roughness), 0.0316);  // (Ns 2000 at most)
    append_values(out, "Ns", {float(2 / (r * r) - 2)});
    const char* keys[] = {"map_Kd", "norm", "map_Ke"};  // (MaterialLook::textures' order)
    for (size_t k = 0; k < 3; ++k)
      if (const std::string& texture = *look.textures()[k]; !texture.empty()) out += std::string(keys[k]) + ' ' + io::path_from(texture, folder) + '\n';
  }
}

std::vector<MtlMaterial> read_mtl(std::span<const uint8_t> bytes, const std::string& name, const std::filesystem::path& folder) {
  std::vector<MtlMaterial> out;
  io::TextReader in(bytes, name);
  in.set_comment('#');
  bool roughness_given = false;
  float shininess = -1;
  // Ns (a Phong exponent) stands for roughness when Pr does not: the exponent whose lobe a GGX
  // roughness r matches, 2 / r^2 - 2 (r = 1 at Ns 0).
  const auto finish = [&] {
    if (!out.empty() && !roughness_given && shininess >= 0) out.back().look.roughness = float(std::sqrt(2.0 / (shininess + 2.0)));
  };
  for (;;) {
    in.skip_empty_lines('#');
    if (in.at_end()) break;
    const std::string_view key = in.token();
    if (key == "newmtl") {
      finish();
      const std::string_view material = in.rest_of_line();
      if (material.empty()) in.fail("newmtl names no material");
      out.push_back({std::string(material), {}});
      roughness_given = false, shininess = -1;
    } else if (out.empty()) {
      std::string what(key);  // (built in steps: g++ 12 warns falsely of "'" + string + ...)
      in.fail(what.append(" before the first newmtl"));
    } else {
      MaterialLook& look = out.back().look;
      if (key == "Kd") {
        const float3 c = read_rgb(in, "Kd colour");
        look.base_color = {c.x, c.y, c.z, look.base_color.w};
      } else if (key == "d") {
        look.base_color.w = std::clamp(in.read_float("d (dissolve)"), 0.0f, 1.0f);
      } else if (key == "Tr") {
        look.base_color.w = 1 - std::clamp(in.read_float("Tr (transparency)"), 0.0f, 1.0f);
      } else if (key == "Ke") {
        look.emissive = read_rgb(in, "Ke colour");
      } else if (key == "Pm") {
        look.metallic = std::clamp(in.read_float("Pm (metallic)"), 0.0f, 1.0f);
      } else if (key == "Pr") {
        look.roughness = std::clamp(in.read_float("Pr (roughness)"), 0.0f, 1.0f);
        roughness_given = true;
      } else if (key == "Ns") {
        shininess = std::max(in.read_float("Ns (shininess)"), 0.0f);
      } else if (key == "map_Kd") {
        look.base_color_texture = texture_path(in, folder);
      } else if (key == "norm" || key == "map_Bump" || key == "map_bump" || key == "bump") {
        look.normal_texture = texture_path(in, folder);
      } else if (key == "map_Ke") {
        look.emissive_texture = texture_path(in, folder);
      }
    }
    in.next_line();
  }
  finish();
  return out;
}

}  // namespace lod
