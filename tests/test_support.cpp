#include "test_support.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <map>
#include <fstream>
#include <random>
#include <sstream>

#include <gtest/gtest.h>

#include "lodkit/error.h"
#include "lodkit/io.h"

extern char** environ;

namespace lod::test {

TempDir::TempDir() {
  std::random_device rd;
  for (;;) {
    path = std::filesystem::temp_directory_path() / ("lodkit-test-" + std::to_string(rd()));
    if (std::filesystem::create_directory(path)) break;
  }
}
TempDir::~TempDir() {
  std::error_code ec;
  std::filesystem::remove_all(path, ec);
}

RunResult run_cli(const std::vector<std::string>& args, uint64_t address_space_limit) {
  std::vector<std::string> argv = {LODKIT_CLI};
  argv.insert(argv.end(), args.begin(), args.end());
  return run_program(std::move(argv), address_space_limit);
}

bool program_available(const std::string& name) {
  return std::system(("command -v '" + name + "' >/dev/null 2>&1").c_str()) == 0;
}

RunResult run_program(std::vector<std::string> argv_s, uint64_t address_space_limit) {
  // prlimit (util-linux) caps the child's address space: an allocation for a declared count fails.
  if (address_space_limit) argv_s.insert(argv_s.begin(), {"/usr/bin/prlimit", "--as=" + std::to_string(address_space_limit)});
  TempDir tmp;
  std::string out_path = (tmp.path / "out").string(), err_path = (tmp.path / "err").string();
  std::vector<char*> argv;
  for (auto& a : argv_s) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&fa, 2, err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
  pid_t pid = 0;
  RunResult r;
  if (posix_spawnp(&pid, argv[0], &fa, nullptr, argv.data(), environ) != 0) {
    posix_spawn_file_actions_destroy(&fa);
    r.err = std::string("spawn failed: ") + std::strerror(errno);
    return r;
  }
  posix_spawn_file_actions_destroy(&fa);
  int status = 0;
  waitpid(pid, &status, 0);
  if (WIFEXITED(status)) r.exit_code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) r.signal = WTERMSIG(status);
  std::ifstream o(out_path), e(err_path);
  std::stringstream so, se;
  so << o.rdbuf();
  se << e.rdbuf();
  r.out = so.str();
  r.err = se.str();
  return r;
}

std::filesystem::path corpus_dir() {
  std::filesystem::path p = LODKIT_CORPUS_DIR;
  std::error_code ec;
  if (std::filesystem::exists(p / "bunny00.off", ec)) return p;
  return {};
}

std::vector<std::filesystem::path> corpus_files() {
  std::vector<std::filesystem::path> files;
  auto dir = corpus_dir();
  if (dir.empty()) return files;
  for (auto& e : std::filesystem::directory_iterator(dir))
    if (e.is_regular_file()) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  return files;
}

void write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary);
  f << text;
}
void write_bytes(const std::filesystem::path& path, const std::vector<uint8_t>& bytes) {
  std::ofstream f(path, std::ios::binary);
  f.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
}

std::string read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

std::string base64(std::span<const uint8_t> bytes) {
  static const char digits[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (size_t i = 0; i < bytes.size(); i += 3) {
    uint32_t v = uint32_t(bytes[i]) << 16;
    if (i + 1 < bytes.size()) v |= uint32_t(bytes[i + 1]) << 8;
    if (i + 2 < bytes.size()) v |= bytes[i + 2];
    out += digits[v >> 18];
    out += digits[(v >> 12) & 63];
    out += i + 1 < bytes.size() ? digits[(v >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? digits[v & 63] : '=';
  }
  return out;
}

std::vector<uint8_t> from_base64(const std::string& text) {
  std::vector<uint8_t> out;
  uint32_t v = 0;
  int bits = 0;
  for (const char c : text) {
    int d = -1;
    if (c >= 'A' && c <= 'Z') d = c - 'A';
    else if (c >= 'a' && c <= 'z') d = c - 'a' + 26;
    else if (c >= '0' && c <= '9') d = c - '0' + 52;
    else if (c == '+') d = 62;
    else if (c == '/') d = 63;
    if (d < 0) continue;
    v = (v << 6) | uint32_t(d), bits += 6;
    if (bits >= 8) bits -= 8, out.push_back(uint8_t(v >> bits));
  }
  return out;
}

namespace {
template <class T>
bool bits_equal(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}
template <class T>
std::string first_diff(const char* what, const std::vector<T>& a, const std::vector<T>& b) {
  if (a.size() != b.size())
    return std::string(what) + ": size " + std::to_string(a.size()) + " vs " + std::to_string(b.size());
  for (size_t i = 0; i < a.size(); ++i)
    if (std::memcmp(&a[i], &b[i], sizeof(T)) != 0) return std::string(what) + ": first difference at " + std::to_string(i);
  return {};
}
}  // namespace

void add_tangents(Mesh& m) {
  m.tangents.clear();
  for (size_t v = 0; v < m.normals.size(); ++v) {
    const float3 n = m.normals[v];
    const float len = std::hypot(n.x, n.y);
    m.tangents.push_back(len > 1e-3f ? float4{-n.y / len, n.x / len, 0, v % 2 ? -1.0f : 1.0f} : float4{1, 0, 0, v % 2 ? -1.0f : 1.0f});
  }
}

std::vector<std::array<uint32_t, 3>> canonical_triangles(const std::vector<uint32_t>& indices, const std::vector<uint32_t>* map) {
  std::vector<std::array<uint32_t, 3>> out;
  for (size_t t = 0; t + 2 < indices.size(); t += 3) {
    std::array<uint32_t, 3> c;
    for (size_t k = 0; k < 3; ++k) c[k] = map ? (*map)[indices[t + k]] : indices[t + k];
    std::rotate(c.begin(), std::min_element(c.begin(), c.end()), c.end());
    out.push_back(c);
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::string mesh_difference(const Mesh& a, const Mesh& b) {
  std::string d;
  auto check = [&](const char* what, const auto& x, const auto& y) {
    if (d.empty() && !bits_equal(x, y)) d = first_diff(what, x, y);
  };
  check("positions", a.positions, b.positions);
  check("normals", a.normals, b.normals);
  check("tangents", a.tangents, b.tangents);
  for (size_t k = 0; k < max_uv_sets; ++k) check("uvs", a.uvs[k], b.uvs[k]);
  check("colors", a.colors, b.colors);
  check("joints", a.joints, b.joints);
  check("weights", a.weights, b.weights);
  check("second-set joints", a.joints1, b.joints1);
  check("second-set weights", a.weights1, b.weights1);
  check("indices", a.indices, b.indices);
  check("materials", a.materials, b.materials);
  check("groups", a.groups, b.groups);
  return d;
}

std::string expect_bad_input(const Reader& read, const std::string& input, const std::string& name) {
  try {
    read(bytes_of(input), name);
  } catch (const Error& e) {
    EXPECT_EQ(e.category(), ErrorCategory::bad_input) << e.what();
    EXPECT_EQ(std::string(e.what()).rfind(name + ":", 0), 0u) << e.what();
    return e.what();
  }
  ADD_FAILURE() << name << " accepted: " << input.substr(0, 200);
  return {};
}

static std::filesystem::path validator_script() { return std::filesystem::path(LODKIT_SOURCE_DIR) / "tests/gltf-validator/validate.mjs"; }

bool second_reader_available() {
  std::error_code ec;
  return std::filesystem::exists(std::filesystem::path(LODKIT_SOURCE_DIR) / "tests/gltf-loader/node_modules/@gltf-transform/core", ec) &&
         std::system("command -v node >/dev/null 2>&1") == 0;
}

nlohmann::json read_with_second_reader(const std::filesystem::path& file, const std::string& flag) {
  std::vector<std::string> argv = {"node", (std::filesystem::path(LODKIT_SOURCE_DIR) / "tests/gltf-loader/load.mjs").string(), file.string()};
  if (!flag.empty()) argv.push_back(flag);
  const RunResult r = run_program(argv);
  EXPECT_EQ(r.exit_code, 0) << file << ": " << r.err;
  return r.exit_code == 0 ? nlohmann::json::parse(r.out) : nlohmann::json::array();
}

bool validator_available() {
  std::error_code ec;
  return std::filesystem::exists(std::filesystem::path(LODKIT_SOURCE_DIR) / "tests/gltf-validator/node_modules/gltf-validator", ec) &&
         std::system("command -v node >/dev/null 2>&1") == 0;
}

ValidatorRun run_validator(const std::vector<std::filesystem::path>& files) {
  std::string command = "node '" + validator_script().string() + "'";
  for (const auto& f : files) command += " '" + f.string() + "'";
  command += " 2>&1";
  ValidatorRun run;
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return run;
  char buffer[4096];
  size_t n;
  while ((n = fread(buffer, 1, sizeof buffer, pipe)) > 0) run.output.append(buffer, n);
  const int status = pclose(pipe);
  run.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return run;
}

void expect_valid_gltf(const std::vector<std::filesystem::path>& files) {
  if (!validator_available()) GTEST_SKIP() << "gltf-validator not installed (scripts/setup.sh installs it)";
  const ValidatorRun v = run_validator(files);
  EXPECT_EQ(v.status, 0) << v.output;
  for (const std::filesystem::path& file : files)
    EXPECT_NE(v.output.find(file.filename().string() + ": 0 errors"), std::string::npos) << v.output;
}

uint32_t little_u32(const uint8_t* p) { return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24; }

Glb read_glb(const std::filesystem::path& path) {
  const FileBytes bytes = read_file_bytes(path);
  if (bytes.size() < 20) throw std::runtime_error(path.string() + ": not a GLB");
  const uint32_t json_length = little_u32(bytes.data() + 12);
  Glb glb;
  glb.doc = nlohmann::json::parse(std::string(reinterpret_cast<const char*>(bytes.data()) + 20, json_length));
  const size_t bin_at = 20 + size_t(json_length);
  if (bytes.size() >= bin_at + 8) {
    const uint32_t bin_length = little_u32(bytes.data() + bin_at);
    glb.bin.assign(bytes.data() + bin_at + 8, bytes.data() + bin_at + 8 + bin_length);
  }
  return glb;
}

std::string tiny_png() {
  return std::string(
      "\x89\x50\x4e\x47\x0d\x0a\x1a\x0a\x00\x00\x00\x0d\x49\x48\x44\x52\x00\x00\x00\x01\x00\x00\x00\x01\x08\x02\x00\x00"
      "\x00\x90\x77\x53\xde\x00\x00\x00\x0c\x49\x44\x41\x54\x78\x9c\x63\xf8\xdf\xc0\x00\x00\x04\x01\x01\x80\xc5\x2a\x18"
      "\x5d\x00\x00\x00\x00\x49\x45\x4e\x44\xae\x42\x60\x82",
      69);
}

std::vector<uint8_t> glb_bytes(const Glb& glb) {
  std::string text = glb.doc.dump();
  while (text.size() % 4) text += ' ';
  std::vector<uint8_t> bin = glb.bin;
  while (bin.size() % 4) bin.push_back(0);
  std::vector<uint8_t> out;
  const auto put = [&](uint32_t v) {
    for (int i = 0; i < 4; ++i) out.push_back(uint8_t(v >> (8 * i)));
  };
  put(0x46546C67);  // "glTF"
  put(2);
  put(uint32_t(12 + 8 + text.size() + (bin.empty() ? 0 : 8 + bin.size())));
  put(uint32_t(text.size()));
  put(0x4E4F534A);  // "JSON"
  out.insert(out.end(), text.begin(), text.end());
  if (!bin.empty()) {
    put(uint32_t(bin.size()));
    put(0x004E4942);  // "BIN\0"
    out.insert(out.end(), bin.begin(), bin.end());
  }
  return out;
}

nlohmann::json glb_json(const std::filesystem::path& path) { return read_glb(path).doc; }

namespace {
std::vector<float> accessor_floats(const Glb& glb, size_t index) {
  const nlohmann::json& accessor = glb.doc["accessors"][index];
  const auto& view = glb.doc["bufferViews"][accessor["bufferView"].get<size_t>()];
  const uint8_t* data = glb.bin.data() + view.value("byteOffset", size_t(0)) + accessor.value("byteOffset", size_t(0));
  const std::map<std::string, size_t> components = {{"SCALAR", 1}, {"VEC2", 2}, {"VEC3", 3}, {"VEC4", 4}};
  std::vector<float> out(accessor["count"].get<size_t>() * components.at(accessor["type"].get<std::string>()));
  std::memcpy(out.data(), data, out.size() * sizeof(float));
  return out;
}
}  // namespace

std::vector<float> glb_floats(const std::filesystem::path& path, size_t accessor) { return accessor_floats(read_glb(path), accessor); }

std::vector<float3> glb_morph_positions(const std::filesystem::path& path, size_t mesh, size_t primitive, size_t target) {
  const Glb glb = read_glb(path);
  const auto& prim = glb.doc["meshes"][mesh]["primitives"][primitive];
  if (!prim.contains("targets") || prim["targets"].size() <= target) return {};
  const std::vector<float> floats = accessor_floats(glb, prim["targets"][target]["POSITION"].get<size_t>());
  std::vector<float3> out;
  for (size_t i = 0; i + 2 < floats.size(); i += 3) out.push_back({floats[i], floats[i + 1], floats[i + 2]});
  return out;
}

double triangle_distance(const float3& p, const float3& a, const float3& b, const float3& c) {
  const auto sub = [](const float3& x, const float3& y) {
    return std::array<double, 3>{double(x.x) - y.x, double(x.y) - y.y, double(x.z) - y.z};
  };
  const auto dot = [](const std::array<double, 3>& x, const std::array<double, 3>& y) { return x[0] * y[0] + x[1] * y[1] + x[2] * y[2]; };
  const auto segment = [&](const float3& s, const float3& e) {
    const std::array<double, 3> se = sub(e, s), sp = sub(p, s);
    const double len2 = dot(se, se), t = len2 > 0 ? std::clamp(dot(sp, se) / len2, 0.0, 1.0) : 0.0;
    const std::array<double, 3> r{sp[0] - t * se[0], sp[1] - t * se[1], sp[2] - t * se[2]};
    return std::sqrt(dot(r, r));
  };
  const std::array<double, 3> u = sub(b, a), w = sub(c, a), ap = sub(p, a);
  const double uu = dot(u, u), uw = dot(u, w), ww = dot(w, w), pu = dot(ap, u), pw = dot(ap, w);
  const double det = uu * ww - uw * uw;
  if (det > 0) {
    const double s = (pu * ww - pw * uw) / det, t = (pw * uu - pu * uw) / det;
    if (s >= 0 && t >= 0 && s + t <= 1) {
      const std::array<double, 3> r{ap[0] - s * u[0] - t * w[0], ap[1] - s * u[1] - t * w[1], ap[2] - s * u[2] - t * w[2]};
      return std::sqrt(dot(r, r));
    }
  }
  return std::min({segment(a, b), segment(b, c), segment(c, a)});
}

}  // namespace lod::test
