// Render benchmark: a 1024x768 picture of a mesh of over a million triangles on this machine's GL
// (Mesa llvmpipe without a GPU). scripts/bench.sh render drives it and adds peak memory.
//
//   lodkit_bench_render make-input data/corpus/bunny00.off build/bench-data/render/bunny-1m.ply
//   lodkit_bench_render run build/bench-data/render/bunny-1m.ply RUNS [WIDTHxHEIGHT] --json
//
// make-input subdivides 1 -> 4 until the mesh has at least 1M triangles (bunny00: twice, 1,206,528)
// and writes a binary PLY, kept when it is newer than the source. run loads it once, makes the
// context once, then RUNS times uploads the mesh (normals computed: the PLY has none), draws it
// (4x MSAA, smooth, iso view), reads colour and depth back and encodes the PNG, timing each step; it
// prints one JSON line with every run and the medians.
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "lodkit/error.h"
#include "lodkit/io.h"
#include "lodkit/render.h"
#include "median.h"

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

int make_input(const std::filesystem::path& source, const std::filesystem::path& out) {
  std::error_code ec;
  if (std::filesystem::exists(out, ec) &&
      std::filesystem::last_write_time(out, ec) > std::filesystem::last_write_time(source, ec)) {
    std::fprintf(stderr, "bench: %s is up to date\n", out.string().c_str());
    return 0;
  }
  lod::Mesh mesh = lod::read_mesh(source);
  while (mesh.triangle_count() < 1'000'000) mesh = lod::subdivide_midpoint(mesh);
  std::filesystem::create_directories(out.parent_path(), ec);
  lod::write_mesh(mesh, out);
  std::fprintf(stderr, "bench: wrote %s (%zu triangles)\n", out.string().c_str(), mesh.triangle_count());
  return 0;
}

int run(const std::filesystem::path& input, int runs, uint32_t width, uint32_t height) {
  auto start = Clock::now();
  const lod::Mesh mesh = lod::read_mesh(input);
  const double load = since(start);
  start = Clock::now();
  lod::RenderContext gl;
  const double context = since(start);
  const lod::RenderOptions options{.width = width, .height = height, .samples = 4};
  std::vector<double> upload, draw, encode, total;
  size_t png_bytes = 0;
  for (int r = 0; r < runs; ++r) {
    auto t = Clock::now();
    const lod::GpuMesh gpu(gl, mesh);
    upload.push_back(since(t));
    t = Clock::now();
    const lod::RenderCamera camera =
        lod::fit_camera(gpu.bounds(), lod::view_direction("iso"), double(width) / height);
    const lod::Image image = lod::render(gl, gpu, camera, options);  // draw, resolve, read back
    draw.push_back(since(t));
    t = Clock::now();
    png_bytes = lod::encode_png(image).size();
    encode.push_back(since(t));
    total.push_back(upload.back() + draw.back() + encode.back());
  }
  const nlohmann::json j = {{"input", input.string()},
                            {"triangles", mesh.triangle_count()},
                            {"vertices", mesh.vertex_count()},
                            {"width", width},
                            {"height", height},
                            {"samples", std::min(4u, gl.max_samples())},
                            {"renderer", gl.renderer()},
                            {"runs", runs},
                            {"load_seconds", load},
                            {"context_seconds", context},
                            {"upload_seconds", upload},
                            {"draw_seconds", draw},
                            {"encode_seconds", encode},
                            {"median_upload_seconds", bench::median(upload)},
                            {"median_draw_seconds", bench::median(draw)},
                            {"median_encode_seconds", bench::median(encode)},
                            {"median_render_seconds", bench::median(total)},
                            {"png_bytes", png_bytes}};
  std::printf("%s\n", j.dump().c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const std::string mode = argc > 1 ? argv[1] : "";
    if (mode == "make-input" && argc == 4) return make_input(argv[2], argv[3]);
    if (mode == "run" && argc >= 4) {
      uint32_t width = 1024, height = 768;
      if (argc >= 5 && std::string(argv[4]) != "--json" && std::sscanf(argv[4], "%ux%u", &width, &height) != 2) {
        std::fprintf(stderr, "bench: bad size %s\n", argv[4]);
        return 1;
      }
      const int runs = std::stoi(argv[3]);
      if (runs < 1) throw lod::Error(lod::ErrorCategory::usage, "RUNS must be at least 1");
      return run(argv[2], runs, width, height);
    }
    std::fprintf(stderr,
                 "usage: lodkit_bench_render make-input SOURCE OUT.ply | run IN RUNS [WIDTHxHEIGHT] [--json]\n");
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench: %s\n", e.what());
    return 2;
  }
}
