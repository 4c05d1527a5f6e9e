#include "io/text_reader.h"

#include <cmath>
#include <string>

namespace lod::io {

namespace {
// from_chars does not accept a leading '+', which some exporters write.
const char* skip_plus(const char* s, const char* e) { return (s < e && *s == '+') ? s + 1 : s; }
}  // namespace

double TextReader::read_double(const char* what) {
  std::string_view t = token();
  if (t.empty()) fail(std::string("expected ") + what + ", found end of line");
  const char* s = skip_plus(t.data(), t.data() + t.size());
  double v = 0;
  auto [ptr, ec] = std::from_chars(s, t.data() + t.size(), v);
  if (ec == std::errc::result_out_of_range) fail(std::string(what) + " is out of range: '" + std::string(t) + "'");
  if (ec != std::errc() || ptr != t.data() + t.size())
    fail(std::string("expected ") + what + ", found '" + std::string(t.substr(0, 40)) + "'");
  if (!std::isfinite(v)) fail(std::string(what) + " is not finite: '" + std::string(t) + "'");
  return v;
}

bool parse_float(std::string_view t, float& v) {
  const char* s = skip_plus(t.data(), t.data() + t.size());
  auto [ptr, ec] = std::from_chars(s, t.data() + t.size(), v);
  // Denormal underflow reports out_of_range; that value is still a usable (tiny) float.
  if (ec == std::errc::result_out_of_range && std::isfinite(v) && std::fabs(v) < 1.0f) ec = std::errc();
  return !t.empty() && ec == std::errc() && ptr == t.data() + t.size() && std::isfinite(v);
}

float TextReader::read_float(const char* what) {
  std::string_view t = token();
  if (t.empty()) fail(std::string("expected ") + what + ", found end of line");
  float v = 0;
  if (!parse_float(t, v)) fail(std::string("expected ") + what + " (a finite number), found '" + std::string(t.substr(0, 40)) + "'");
  return v;
}

bool TextReader::try_read_float(float& value) {
  if (at_line_end()) return false;
  value = read_float("a number");
  return true;
}

template <class Integer>
Integer TextReader::read_integer(const char* what, const char* kind) {
  std::string_view t = token();
  if (t.empty()) fail(std::string("expected ") + what + ", found end of line");
  const char* s = skip_plus(t.data(), t.data() + t.size());
  Integer v = 0;
  auto [ptr, ec] = std::from_chars(s, t.data() + t.size(), v);
  if (ec != std::errc() || ptr != t.data() + t.size())
    fail(std::string("expected ") + what + " (" + kind + "), found '" + std::string(t.substr(0, 40)) + "'");
  return v;
}

int64_t TextReader::read_int(const char* what) { return read_integer<int64_t>(what, "an integer"); }
uint64_t TextReader::read_uint(const char* what) { return read_integer<uint64_t>(what, "a non-negative integer"); }

std::filesystem::path relative_path(const std::filesystem::path& file, const std::filesystem::path& folder) {
  std::error_code ec;
  const std::filesystem::path from = std::filesystem::absolute(file, ec).lexically_normal();
  const std::filesystem::path there = std::filesystem::absolute(folder.empty() ? "." : folder, ec).lexically_normal();
  if (ec) return {};
  return from.lexically_relative(there);
}

std::string path_from(const std::filesystem::path& file, const std::filesystem::path& folder) {
  const std::filesystem::path relative = relative_path(file, folder);
  std::error_code ec;
  return (relative.empty() ? std::filesystem::absolute(file, ec).lexically_normal() : relative).generic_string();
}

void append_float(std::string& out, float value) {
  char buf[32];
  // Shortest round-trip form: reading it back with from_chars gives the same bits.
  auto [ptr, ec] = std::to_chars(buf, buf + sizeof(buf), value);
  (void)ec;
  out.append(buf, ptr);
}

void append_uint(std::string& out, uint64_t value) {
  char buf[24];
  auto [ptr, ec] = std::to_chars(buf, buf + sizeof(buf), value);
  (void)ec;
  out.append(buf, ptr);
}

}  // namespace lod::io
