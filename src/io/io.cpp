// Format dispatch: the file-level functions pick the reader or writer from the extension.
#include <algorithm>
#include <cctype>
#include <map>

#include "lodkit/error.h"
#include "lodkit/io.h"

namespace lod {

namespace {

std::string lower_extension(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext;
}

void warn(const ReadOptions& options, const std::string& message) {
  if (options.warning) options.warning(message);
}

// The library names of mtllib statements: a statement's text is one file name, or failing that
// several blank-separated ones.
std::vector<std::string> library_names(const std::vector<std::string>& statements, const std::filesystem::path& folder) {
  std::vector<std::string> names;
  for (const std::string& text : statements) {
    std::error_code ec;
    if (std::filesystem::is_regular_file(folder / std::filesystem::path(text), ec)) {
      names.push_back(text);
      continue;
    }
    for (size_t i = 0; i < text.size();) {
      const size_t end = std::min(text.find_first_of(" \t", i), text.size());
      if (end > i) names.push_back(text.substr(i, end - i));
      i = end + 1;
    }
  }
  return names;
}

// Mesh::material_looks of an OBJ from the MTL libraries its mtllib statements name, beside it. A
// library or a texture that is not there is a warning, not an error: the mesh is whole, and its
// materials keep their names.
void read_material_looks(Mesh& mesh, const std::vector<std::string>& statements, const std::filesystem::path& obj,
                         const ReadOptions& options) {
  if (mesh.material_names.empty() || statements.empty()) return;
  const std::filesystem::path folder = obj.parent_path();
  std::vector<MtlMaterial> materials;
  for (const std::string& name : library_names(statements, folder)) {
    const std::filesystem::path file = folder / std::filesystem::path(name);
    std::error_code ec;
    if (!std::filesystem::is_regular_file(file, ec)) {
      warn(options, obj.string() + ": material library " + name + " not found: its materials keep only their names");
      continue;
    }
    std::vector<MtlMaterial> read = read_mtl(read_file_bytes(file), file.string(), file.parent_path());
    materials.insert(materials.end(), std::make_move_iterator(read.begin()), std::make_move_iterator(read.end()));
  }
  if (materials.empty()) return;
  mesh.material_looks.assign(mesh.material_names.size(), MaterialLook{});
  size_t missing = 0;
  std::string first_missing;
  for (size_t id = 0; id < mesh.material_names.size(); ++id) {
    // The first definition of a name counts, as in the readers lodkit's peers use.
    const auto it = std::find_if(materials.begin(), materials.end(), [&](const MtlMaterial& m) { return m.name == mesh.material_names[id]; });
    if (it == materials.end()) {
      if (!mesh.material_names[id].empty() && !missing++) first_missing = mesh.material_names[id];
      continue;
    }
    mesh.material_looks[id] = it->look;
    for (const std::string* texture : it->look.textures()) {
      std::error_code ec;
      if (!texture->empty() && !std::filesystem::is_regular_file(std::filesystem::path(*texture), ec))
        warn(options, obj.string() + ": material " + it->name + "'s texture " + *texture + " not found");
    }
  }
  if (missing)
    warn(options, obj.string() + ": " + std::to_string(missing) + " material(s) in no material library (" + first_missing +
                      (missing > 1 ? ", ...)" : ")") + ": they keep only their names");
}

// Mesh::material_looks of a PLY from its TextureFile comments (MeshLab's): texnumber k (its
// material id) takes texture k, beside the file, and the texture's file name as its material's name
// where it has none. A texture that is not there is a warning.
void read_texture_looks(Mesh& mesh, const std::vector<std::string>& textures, const std::filesystem::path& ply,
                        const ReadOptions& options) {
  if (textures.empty() || mesh.triangle_count() == 0) return;
  uint32_t ids = 1;
  for (uint32_t id : mesh.materials) ids = std::max(ids, id + 1);
  const size_t count = std::max({size_t(ids), textures.size(), mesh.material_names.size()});
  mesh.material_names.resize(count);
  mesh.material_looks.assign(count, MaterialLook{});
  for (size_t k = 0; k < textures.size(); ++k) {
    const std::filesystem::path file = (ply.parent_path() / std::filesystem::path(textures[k])).lexically_normal();
    std::error_code ec;
    if (!std::filesystem::is_regular_file(file, ec)) warn(options, ply.string() + ": texture " + textures[k] + " not found");
    mesh.material_looks[k].base_color_texture = file.string();
    if (mesh.material_names[k].empty()) mesh.material_names[k] = textures[k];
  }
}

// OBJ, PLY, OFF or STL.
Mesh read_plain(const FileBytes& bytes, FileFormat format, const std::filesystem::path& path, const ReadOptions& options) {
  switch (format) {
    case FileFormat::obj: {
      std::vector<std::string> libraries;
      Mesh mesh = read_obj(bytes, path.string(), options, &libraries);
      read_material_looks(mesh, libraries, path, options);
      return mesh;
    }
    case FileFormat::ply: {
      std::vector<std::string> textures;
      Mesh mesh = read_ply(bytes, path.string(), options, &textures);
      read_texture_looks(mesh, textures, path, options);
      return mesh;
    }
    case FileFormat::off: return read_off(bytes, path.string(), options);
    default: return read_stl(bytes, path.string(), options);
  }
}

}  // namespace

FileFormat format_from_path(const std::filesystem::path& path) {
  const std::string ext = lower_extension(path);
  if (ext == ".obj") return FileFormat::obj;
  if (ext == ".ply") return FileFormat::ply;
  if (ext == ".off") return FileFormat::off;
  if (ext == ".stl") return FileFormat::stl;
  if (ext == ".gltf") return FileFormat::gltf;
  if (ext == ".glb") return FileFormat::glb;
  throw_usage(path.string() + ": unknown mesh format '" + ext + "' (expected .obj .ply .off .stl .gltf .glb)");
}

std::filesystem::path gltf_buffer_path(const std::filesystem::path& path) {
  if (lower_extension(path) != ".gltf") return {};
  return path.parent_path() / (path.stem().string() + ".bin");
}

std::filesystem::path obj_library_path(const std::filesystem::path& path) {
  if (lower_extension(path) != ".obj") return {};
  return path.parent_path() / (path.stem().string() + ".mtl");
}

std::vector<std::filesystem::path> obj_material_libraries(const std::filesystem::path& path) {
  // The mtllib lines alone (the OBJ reader's keyword at a line's start), not a whole parse.
  const FileBytes bytes = read_file_bytes(path);
  const std::string_view text(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  std::vector<std::string> statements;
  for (size_t at = 0; at < text.size();) {
    const size_t end = std::min(text.find_first_of("\r\n", at), text.size());
    std::string_view line = text.substr(at, end - at);
    line.remove_prefix(std::min(line.find_first_not_of(" \t"), line.size()));
    if (line.starts_with("mtllib") && line.size() > 6 && (line[6] == ' ' || line[6] == '\t')) {
      line.remove_prefix(6);
      line.remove_prefix(std::min(line.find_first_not_of(" \t"), line.size()));
      line.remove_suffix(line.size() - std::min(line.find_last_not_of(" \t") + 1, line.size()));
      statements.emplace_back(line);
    }
    at = end + 1;
  }
  std::vector<std::filesystem::path> files;
  for (const std::string& name : library_names(statements, path.parent_path())) {
    std::error_code ec;
    if (std::filesystem::is_regular_file(path.parent_path() / name, ec)) files.push_back(path.parent_path() / name);
  }
  return files;
}

const char* format_name(FileFormat format) {
  switch (format) {
    case FileFormat::obj: return "OBJ";
    case FileFormat::ply: return "PLY";
    case FileFormat::off: return "OFF";
    case FileFormat::stl: return "STL";
    case FileFormat::gltf: return "glTF";
    case FileFormat::glb: return "GLB";
  }
  return "?";
}

Scene read_scene(const std::filesystem::path& path, const ReadOptions& options) {
  FileFormat format = format_from_path(path);
  const FileBytes bytes = read_file_bytes(path);
  if (format == FileFormat::gltf || format == FileFormat::glb) {
    std::filesystem::path base = path.has_parent_path() ? path.parent_path() : std::filesystem::path(".");
    return read_gltf(bytes, path.string(), base, options);
  }
  return scene_from_mesh(read_plain(bytes, format, path, options));
}

Mesh read_mesh(const std::filesystem::path& path, const ReadOptions& options) {
  FileFormat format = format_from_path(path);
  if (format == FileFormat::gltf || format == FileFormat::glb) return flatten(read_scene(path, options));
  return read_plain(read_file_bytes(path), format, path, options);
}

namespace {

// An OBJ or PLY can only name texture files: the images a glTF embedded (MaterialLook::images) that
// its triangles' materials use go beside it, OUT_k.png or OUT_k.jpg (k in order of first use; a name
// a look already uses as its texture file is passed over, so the file it names is not replaced).
// Returns the mesh to write: `mesh`, or `named`, its copy naming the files.
const Mesh& with_image_files(const Mesh& mesh, const std::filesystem::path& path, Mesh& named, uint64_t& bytes) {
  const std::vector<bool> used = used_materials(mesh, mesh.material_looks.size());
  const auto embeds = [&](size_t id) {
    const auto& images = mesh.material_looks[id].images;
    return used[id] && std::any_of(images.begin(), images.end(), [](const auto& image) { return image != nullptr; });
  };
  size_t id = 0;
  while (id < used.size() && !embeds(id)) ++id;
  if (id == used.size()) return mesh;
  std::error_code ec;  // (compared as absolute paths: the output's may be relative, the looks' not)
  const auto absolute = [&](const std::filesystem::path& file) { return std::filesystem::absolute(file, ec).lexically_normal(); };
  std::vector<std::filesystem::path> taken;
  for (const MaterialLook& look : mesh.material_looks)
    for (const std::string* file : look.textures())
      if (!file->empty()) taken.push_back(absolute(*file));
  named = mesh;
  std::map<const std::vector<uint8_t>*, std::string> file_of;
  size_t k = 0;
  for (; id < used.size(); ++id) {
    if (!embeds(id)) continue;
    MaterialLook& look = named.material_looks[id];
    for (size_t slot = 0; slot < look.images.size(); ++slot) {
      if (!look.images[slot]) continue;
      const std::vector<uint8_t>& image = *look.images[slot];
      auto [it, inserted] = file_of.try_emplace(&image);
      if (inserted) {
        // (The bytes start as a PNG's or a JPEG's: the glTF reader took no other.)
        const char* extension = !image.empty() && image[0] == 0x89 ? ".png" : ".jpg";
        std::filesystem::path file;
        do {
          file = (path.parent_path() / (path.stem().string() + "_" + std::to_string(k++) + extension)).lexically_normal();
        } while (std::find(taken.begin(), taken.end(), absolute(file)) != taken.end());
        write_file_atomic(file, std::span<const uint8_t>(image));
        bytes += image.size();
        it->second = file.string();
      }
      *look.textures()[slot] = it->second;
      look.images[slot].reset();
    }
  }
  return named;
}

}  // namespace

WriteReport write_mesh(const Mesh& input, const std::filesystem::path& path, const WriteOptions& options) {
  FileFormat format = format_from_path(path);
  if (format == FileFormat::gltf || format == FileFormat::glb) return write_gltf(scene_from_mesh(input), path, options);
  std::string out;
  uint64_t beside_bytes = 0;
  Mesh named;
  const Mesh& mesh = format == FileFormat::obj || format == FileFormat::ply ? with_image_files(input, path, named, beside_bytes) : input;
  switch (format) {
    case FileFormat::obj:
      // The looks go into an MTL library beside it, which the OBJ names first.
      if (!mesh.material_looks.empty()) {
        const std::filesystem::path library = obj_library_path(path);
        std::string mtl;
        write_mtl(mesh, mtl, path.parent_path());
        write_file_atomic(library, mtl);
        beside_bytes += mtl.size();
        out = "mtllib " + library.filename().string() + "\n";
      }
      write_obj(mesh, out, options);
      break;
    case FileFormat::ply: write_ply(mesh, out, options, path.parent_path()); break;
    case FileFormat::off: write_off(mesh, out, options); break;
    default: write_stl(mesh, out, options); break;
  }
  write_file_atomic(path, out);
  return {.bytes = out.size() + beside_bytes};
}

WriteReport write_scene(const Scene& scene, const std::filesystem::path& path, const WriteOptions& options) {
  FileFormat format = format_from_path(path);
  if (format == FileFormat::gltf || format == FileFormat::glb) return write_gltf(scene, path, options);
  return write_mesh(flatten(scene), path, options);
}

}  // namespace lod
