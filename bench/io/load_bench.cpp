// Load-speed benchmark: lodkit's readers against Assimp's on the same files.
//
//   lodkit_bench_io make-inputs MESH OUT_DIR     subdivide MESH 1->4 until >= 3M triangles; write
//                                                OUT_DIR/big.ply (binary LE) and OUT_DIR/big.obj
//   lodkit_bench_io load lodkit|assimp FILE RUNS [--json]
//                                                one untimed warm-up load (page cache), then RUNS timed
//                                                loads; prints median / min / max seconds
//
// scripts/bench.sh io runs each loader in its own process under /usr/bin/time -v for peak memory.
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <fmt/core.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "lodkit/error.h"
#include "lodkit/io.h"
#include "lodkit/mesh.h"

namespace {

struct Loaded {
  size_t vertices = 0, triangles = 0;
};

Loaded load_lodkit(const std::string& file) {
  const lod::Mesh mesh = lod::read_mesh(file);
  return {mesh.vertex_count(), mesh.triangle_count()};
}

// Assimp with aiProcess_Triangulate only: the least post-processing that yields triangles, as lodkit
// gives. No JoinIdenticalVertices (that would be extra work lodkit does not do), no normals generation,
// no validation. Assimp's OBJ importer emits one vertex per face corner; that is its behaviour.
Loaded load_assimp(const std::string& file) {
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(file, aiProcess_Triangulate);
  if (!scene) throw std::runtime_error(std::string("assimp: ") + importer.GetErrorString());
  Loaded loaded;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    loaded.vertices += scene->mMeshes[m]->mNumVertices;
    loaded.triangles += scene->mMeshes[m]->mNumFaces;
  }
  return loaded;
}

// Each output is skipped when it exists and is newer than the source, and written on its own: a writer
// that throws (a format still in progress) costs that file only, not the other one.
int make_inputs(const std::filesystem::path& source, const std::filesystem::path& out_dir) {
  const std::filesystem::path outputs[] = {out_dir / "big.ply", out_dir / "big.obj"};
  auto fresh = [&](const std::filesystem::path& p) {
    return std::filesystem::is_regular_file(p) && std::filesystem::last_write_time(p) >= std::filesystem::last_write_time(source);
  };
  std::vector<std::filesystem::path> stale;
  for (const auto& p : outputs) {
    if (fresh(p))
      fmt::print("up to date: {} ({} MB)\n", p.string(), std::filesystem::file_size(p) >> 20);
    else
      stale.push_back(p);
  }
  if (stale.empty()) return 0;

  lod::Mesh mesh = lod::read_mesh(source);
  const size_t original = mesh.triangle_count();
  int levels = 0;
  while (mesh.triangle_count() < 3'000'000) mesh = lod::subdivide_midpoint(mesh), ++levels;
  fmt::print("{}: {} triangles, subdivided {} times -> {} triangles, {} vertices\n", source.string(), original, levels,
             mesh.triangle_count(), mesh.vertex_count());
  std::filesystem::create_directories(out_dir);
  int status = 0;
  for (const auto& p : stale) {
    try {
      lod::write_mesh(mesh, p, {.binary = true});  // binary little-endian for PLY; OBJ is text regardless
      fmt::print("wrote {} ({} MB)\n", p.string(), std::filesystem::file_size(p) >> 20);
    } catch (const std::exception& e) {
      fmt::print(stderr, "lodkit_bench_io: writing {} failed: {}\n", p.string(), e.what());
      status = 2;
    }
  }
  return status;
}

// A timed load is open + parse + build the in-memory result + free it, for both loaders alike.
int load(const std::string& loader, const std::string& file, int runs, bool json) {
  auto once = [&] { return loader == "lodkit" ? load_lodkit(file) : load_assimp(file); };
  const Loaded loaded = once();  // warm-up: the file is in the page cache for every timed run
  std::vector<double> seconds;
  for (int r = 0; r < runs; ++r) {
    const auto start = std::chrono::steady_clock::now();
    const Loaded again = once();
    seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    if (again.triangles != loaded.triangles) throw std::runtime_error("triangle count changed between runs");
  }
  std::sort(seconds.begin(), seconds.end());
  const double median = runs % 2 ? seconds[size_t(runs / 2)] : 0.5 * (seconds[size_t(runs / 2) - 1] + seconds[size_t(runs / 2)]);
  if (json) {
    nlohmann::json j = {{"loader", loader},       {"file", file},           {"runs", runs},
                        {"median_s", median},     {"min_s", seconds.front()}, {"max_s", seconds.back()},
                        {"triangles", loaded.triangles}, {"vertices", loaded.vertices}};
    fmt::print("{}\n", j.dump());
  } else {
    fmt::print("{:<7} {}: {} triangles, {} vertices; median {:.3f} s (min {:.3f}, max {:.3f}) over {} runs\n", loader, file,
               loaded.triangles, loaded.vertices, median, seconds.front(), seconds.back(), runs);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  try {
    if (args.size() == 3 && args[0] == "make-inputs") return make_inputs(args[1], args[2]);
    if ((args.size() == 4 || (args.size() == 5 && args[4] == "--json")) && args[0] == "load" &&
        (args[1] == "lodkit" || args[1] == "assimp")) {
      const int runs = std::stoi(args[3]);
      if (runs < 1) throw std::invalid_argument("RUNS must be at least 1");
      return load(args[1], args[2], runs, args.size() == 5);
    }
  } catch (const std::exception& e) {
    fmt::print(stderr, "lodkit_bench_io: {}\n", e.what());
    return 2;
  }
  fmt::print(stderr,
             "usage: lodkit_bench_io make-inputs MESH OUT_DIR\n"
             "       lodkit_bench_io load lodkit|assimp FILE RUNS [--json]\n");
  return 1;
}
