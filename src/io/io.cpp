// Format dispatch: the file-level functions pick the reader or writer from the extension.
#include <algorithm>
#include <cctype>

#include "lodkit/error.h"
#include "lodkit/io.h"

namespace lod {

namespace {

std::string lower_extension(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext;
}

// OBJ, PLY, OFF or STL.
Mesh read_plain(const FileBytes& bytes, FileFormat format, const std::filesystem::path& path, const ReadOptions& options) {
  switch (format) {
    case FileFormat::obj: return read_obj(bytes, path.string(), options);
    case FileFormat::ply: return read_ply(bytes, path.string(), options);
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

WriteReport write_mesh(const Mesh& mesh, const std::filesystem::path& path, const WriteOptions& options) {
  FileFormat format = format_from_path(path);
  if (format == FileFormat::gltf || format == FileFormat::glb) return write_gltf(scene_from_mesh(mesh), path, options);
  std::string out;
  switch (format) {
    case FileFormat::obj: write_obj(mesh, out, options); break;
    case FileFormat::ply: write_ply(mesh, out, options); break;
    case FileFormat::off: write_off(mesh, out, options); break;
    default: write_stl(mesh, out, options); break;
  }
  write_file_atomic(path, out);
  return {.bytes = out.size()};
}

WriteReport write_scene(const Scene& scene, const std::filesystem::path& path, const WriteOptions& options) {
  FileFormat format = format_from_path(path);
  if (format == FileFormat::gltf || format == FileFormat::glb) return write_gltf(scene, path, options);
  return write_mesh(flatten(scene), path, options);
}

}  // namespace lod
