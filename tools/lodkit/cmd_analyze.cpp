// lodkit analyze IN: how well the mesh's index buffer suits the GPU as it is, and what lodkit optimize
// would make of it: vertex-cache misses (ACMR, ATVR) for a FIFO and an LRU cache, vertex-fetch
// overfetch, overdraw (as is, in the FIFO cache order, after the overdraw order) and strip statistics
// for both stripifiers and both joins.
#include <fmt/format.h>

#include <chrono>
#include <memory>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "lodkit/error.h"
#include "lodkit/io.h"
#include "lodkit/optimize.h"
#include "progress.h"

namespace lod::cli {

namespace {

struct AnalyzeCommand {
  std::string input;
  uint32_t cache = 16, vertex_size = 0;
  bool json = false;
};

// Bytes per vertex of the streams the mesh has, as 32-bit floats (joints as 16-bit).
uint32_t vertex_bytes(const Mesh& m) {
  uint32_t bytes = 12;
  if (!m.normals.empty()) bytes += 12;
  if (!m.tangents.empty()) bytes += 16;
  bytes += 8 * uint32_t(m.uv_set_count());
  if (!m.colors.empty()) bytes += 16;
  if (!m.joints.empty()) bytes += 8;
  if (!m.weights.empty()) bytes += 16;
  return bytes;
}

}  // namespace

Command register_analyze(CLI::App& root) {
  auto o = std::make_shared<AnalyzeCommand>();
  CLI::App* app = root.add_subcommand("analyze", "Vertex cache (ACMR, ATVR), vertex fetch, overdraw and strip statistics of a mesh");
  app->add_option("input", o->input, "Input mesh file")->required();
  app->add_option("--cache", o->cache, "Vertex cache entries (default 16)");
  app->add_option("--vertex-size", o->vertex_size, "Bytes per vertex for the fetch analysis (default: from the mesh's streams)");
  app->add_flag("--json", o->json, "Print a machine-readable report on stdout");
  return {app, [o] {
            if (o->cache < 3 || o->cache > 64) throw_usage("--cache must be in [3, 64]");
            Mesh mesh;
            {
              ProgressBar bar("loading");
              mesh = read_mesh(o->input, bar.read_options());
            }
            validate(mesh, o->input);
            const size_t V = mesh.vertex_count();
            const uint32_t vertex_size = o->vertex_size ? o->vertex_size : vertex_bytes(mesh);

            struct CacheRow {
              std::string name;
              CachePolicy policy;
              VertexCacheStats as_is, optimized;
            };
            std::vector<CacheRow> cache_rows;
            std::vector<uint32_t> fifo_order;  // the FIFO cache order, for the overdraw rows
            for (const CachePolicy policy : {CachePolicy::fifo, CachePolicy::lru}) {
              const VertexCacheOptions c{.cache_size = o->cache, .policy = policy};
              std::vector<uint32_t> ordered = optimize_vertex_cache(mesh.indices, V, c);
              cache_rows.push_back({fmt::format("{} {}", policy == CachePolicy::fifo ? "FIFO" : "LRU", o->cache), policy,
                                    analyze_vertex_cache(mesh.indices, V, c), analyze_vertex_cache(ordered, V, c)});
              if (policy == CachePolicy::fifo) fifo_order = std::move(ordered);
            }
            // Overdraw (lod::analyze_overdraw: shaded / covered pixels over 14 orthographic views) as the
            // file is, in the FIFO cache order, and after lodkit optimize --overdraw (threshold 1.05).
            constexpr float overdraw_threshold = 1.05f;
            const std::vector<uint32_t> overdraw_ordered =
                optimize_overdraw(fifo_order, mesh.positions, {.cache_size = o->cache, .threshold = overdraw_threshold});
            const VertexCacheOptions fifo{.cache_size = o->cache};
            struct OverdrawRow {
              std::string name;
              OverdrawStats stats;
              VertexCacheStats cache;
            };
            const std::vector<OverdrawRow> overdraw_rows = {
                {"as is", analyze_overdraw(mesh.indices, mesh.positions), cache_rows[0].as_is},
                {"cache order", analyze_overdraw(fifo_order, mesh.positions), cache_rows[0].optimized},
                {fmt::format("overdraw {:g}", overdraw_threshold), analyze_overdraw(overdraw_ordered, mesh.positions),
                 analyze_vertex_cache(overdraw_ordered, V, fifo)}};
            const VertexFetchStats fetch = analyze_vertex_fetch(mesh.indices, V, {.vertex_size = vertex_size, .vertex_cache_size = o->cache});
            struct StripRow {
              std::string name;
              bool restart;
              StripStats stats;
            };
            std::vector<StripRow> strip_rows;
            for (const StripMethod method : {StripMethod::sgi, StripMethod::best})
              for (const bool restart : {false, true}) {
                const Strips s = stripify(mesh.indices, V, {.method = method, .use_restart = restart, .cache_size = o->cache});
                strip_rows.push_back({fmt::format("{} {}", strip_method_name(method), restart ? "restart" : "degenerate"), restart,
                                      analyze_strips(s.indices, restart, s.restart_index)});
              }

            if (o->json) {
              nlohmann::json cache = nlohmann::json::array(), strips = nlohmann::json::array();
              const nlohmann::json overdraw = {{"views", 14}, {"threshold", overdraw_threshold}, {"cache_size", o->cache},
                                               {"as_is", overdraw_rows[0].stats.overdraw},
                                               {"cache_order", overdraw_rows[1].stats.overdraw},
                                               {"overdraw_order", overdraw_rows[2].stats.overdraw},
                                               {"overdraw_order_acmr", overdraw_rows[2].cache.acmr}};
              for (const CacheRow& r : cache_rows)
                cache.push_back({{"policy", cache_policy_name(r.policy)}, {"size", o->cache},
                                 {"misses", r.as_is.misses}, {"acmr", r.as_is.acmr}, {"atvr", r.as_is.atvr},
                                 {"optimized_acmr", r.optimized.acmr}, {"optimized_atvr", r.optimized.atvr}});
              for (const StripRow& r : strip_rows)
                strips.push_back({{"method", r.name.substr(0, r.name.find(' '))}, {"restart", r.restart},
                                  {"indices", r.stats.indices}, {"strips", r.stats.strips},
                                  {"indices_per_triangle", r.stats.indices_per_triangle}});
              const nlohmann::json j = {{"input", o->input}, {"triangles", mesh.triangle_count()}, {"vertices", V},
                                        {"referenced_vertices", cache_rows[0].as_is.referenced_vertices},
                                        {"cache", cache},
                                        {"fetch", {{"vertex_size", vertex_size}, {"bytes_fetched", fetch.bytes_fetched}, {"overfetch", fetch.overfetch}}},
                                        {"overdraw", overdraw},
                                        {"strips", strips}};
              fmt::print("{}\n", j.dump(2));
              return 0;
            }
            fmt::print("{}: {} triangles, {} vertices ({} referenced)\n\n", o->input, mesh.triangle_count(), V,
                       cache_rows[0].as_is.referenced_vertices);
            fmt::print("{:<18}{:>12}{:>10}{:>10}{:>16}{:>16}\n", "vertex cache", "misses", "ACMR", "ATVR", "optimized ACMR", "optimized ATVR");
            for (const CacheRow& r : cache_rows)
              fmt::print("{:<18}{:>12}{:>10.3f}{:>10.3f}{:>16.3f}{:>16.3f}\n", r.name, r.as_is.misses, r.as_is.acmr, r.as_is.atvr,
                         r.optimized.acmr, r.optimized.atvr);
            fmt::print("\n{:<18}{:>12}{:>10}\n", "vertex fetch", "bytes", "overfetch");
            fmt::print("{:<18}{:>12}{:>10.3f}\n", fmt::format("{} B/vertex", vertex_size), fetch.bytes_fetched, fetch.overfetch);
            fmt::print("\n{:<18}{:>12}{:>10}\n", "overdraw", "overdraw", fmt::format("ACMR {}", o->cache));
            for (const OverdrawRow& r : overdraw_rows)
              fmt::print("{:<18}{:>12.3f}{:>10.3f}\n", r.name, r.stats.overdraw, r.cache.acmr);
            fmt::print("\n{:<18}{:>12}{:>10}{:>10}\n", "strips", "indices", "strips", "per tri");
            for (const StripRow& r : strip_rows)
              fmt::print("{:<18}{:>12}{:>10}{:>10.3f}\n", r.name, r.stats.indices, r.stats.strips, r.stats.indices_per_triangle);
            return 0;
          }};
}

}  // namespace lod::cli
