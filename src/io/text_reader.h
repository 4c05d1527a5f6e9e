// Internal: cursors shared by the readers. Every read is bounds-checked and every failure names the
// source and the line (text) or byte offset (binary), so no reader repeats that bookkeeping.
#pragma once

#include <algorithm>
#include <bit>
#include <charconv>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <map>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "lodkit/error.h"
#include "lodkit/io.h"

namespace lod::io {

// Line-oriented tokenizer over a byte buffer. Tokens are separated by spaces/tabs; '\n', "\r\n" and
// '\r' end lines.
class TextReader {
 public:
  // `first_line`: the line number of the first byte (a reader may parse a file in pieces).
  TextReader(std::span<const uint8_t> bytes, const std::string& name, const ReadOptions* options = nullptr,
             uint64_t first_line = 1)
      : begin_(reinterpret_cast<const char*>(bytes.data())), p_(begin_), end_(begin_ + bytes.size()),
        name_(name), options_(options), line_(first_line) {}

  // Treat `c` as starting a comment that runs to the end of the line, even right after a token.
  void set_comment(char c) { comment_ = c; }

  bool at_end() const { return p_ >= end_; }
  uint64_t line() const { return line_; }
  const std::string& name() const { return name_; }
  size_t offset() const { return size_t(p_ - begin_); }
  size_t remaining() const { return size_t(end_ - p_); }

  // Skips spaces and tabs (not newlines).
  void skip_blanks() {
    while (p_ < end_ && (*p_ == ' ' || *p_ == '\t')) ++p_;
  }
  bool at_line_end() {
    skip_blanks();
    return p_ >= end_ || *p_ == '\n' || *p_ == '\r' || (comment_ && *p_ == comment_);
  }
  // Moves past the end of the current line.
  void next_line() {
    while (p_ < end_ && *p_ != '\n' && *p_ != '\r') ++p_;
    if (p_ < end_ && *p_ == '\r') ++p_;
    if (p_ < end_ && *p_ == '\n') ++p_;
    ++line_;
    if (options_ && options_->progress && (line_ & 0x3ffff) == 0)
      options_->progress(double(offset()) / double(end_ > begin_ ? end_ - begin_ : 1));
  }
  // Next blank-separated token on the current line; empty at the line end.
  std::string_view token() {
    skip_blanks();
    const char* s = p_;
    while (p_ < end_ && *p_ != ' ' && *p_ != '\t' && *p_ != '\n' && *p_ != '\r' && (!comment_ || *p_ != comment_)) ++p_;
    return {s, size_t(p_ - s)};
  }
  // The next token without consuming it.
  std::string_view peek_token() {
    const char* save = p_;
    std::string_view t = token();
    p_ = save;
    return t;
  }
  // The rest of the current line with surrounding blanks trimmed (not consumed past the line end).
  std::string_view rest_of_line() {
    skip_blanks();
    const char* s = p_;
    while (p_ < end_ && *p_ != '\n' && *p_ != '\r') ++p_;
    const char* e = p_;
    while (e > s && (e[-1] == ' ' || e[-1] == '\t')) --e;
    return {s, size_t(e - s)};
  }
  // Skips blank lines and lines whose first token starts with `comment` (if non-zero); at_end() after.
  void skip_empty_lines(char comment) {
    for (;;) {
      skip_blanks();
      if (p_ >= end_) return;
      if (*p_ == '\n' || *p_ == '\r' || (comment && *p_ == comment)) {
        next_line();
        continue;
      }
      return;
    }
  }

  float read_float(const char* what);      // finite float, else error
  double read_double(const char* what);    // finite double, else error
  int64_t read_int(const char* what);      // signed integer
  uint64_t read_uint(const char* what);    // unsigned integer
  bool try_read_float(float& value);       // false (nothing consumed) at line end; errors on junk

  [[noreturn]] void fail(const std::string& what) const { throw_bad_input_at_line(name_, line_, what); }

 private:
  template <class Integer>
  Integer read_integer(const char* what, const char* kind);

  const char* begin_;
  const char* p_;
  const char* end_;
  std::string name_;
  const ReadOptions* options_;
  uint64_t line_;
  char comment_ = 0;
};

// Little/big-endian binary cursor with bounds checks.
class BinaryReader {
 public:
  BinaryReader(std::span<const uint8_t> bytes, const std::string& name, size_t offset = 0)
      : bytes_(bytes), name_(name), offset_(offset) {}

  size_t offset() const { return offset_; }
  size_t remaining() const { return offset_ <= bytes_.size() ? bytes_.size() - offset_ : 0; }
  const std::string& name() const { return name_; }
  void seek(size_t offset) { offset_ = offset; }

  // Fails unless `count` items of `item_size` bytes remain; use before reserving for a declared count,
  // so a 200-byte file cannot make us allocate for four billion elements.
  void require(uint64_t count, uint64_t item_size, const char* what) const {
    if (item_size != 0 && count > remaining() / item_size)
      fail(std::string("file declares ") + std::to_string(count) + " " + what + " but only " +
           std::to_string(remaining()) + " bytes remain");
  }
  const uint8_t* take(size_t n, const char* what) {
    if (n > remaining()) fail(std::string("unexpected end of file reading ") + what);
    const uint8_t* p = bytes_.data() + offset_;
    offset_ += n;
    return p;
  }
  template <class T>
  T read(bool big_endian, const char* what) {
    const uint8_t* p = take(sizeof(T), what);
    uint8_t tmp[sizeof(T)];
    if (big_endian)
      for (size_t i = 0; i < sizeof(T); ++i) tmp[i] = p[sizeof(T) - 1 - i];
    else
      std::memcpy(tmp, p, sizeof(T));
    T v;
    std::memcpy(&v, tmp, sizeof(T));
    return v;
  }
  [[noreturn]] void fail(const std::string& what) const { throw_bad_input_at_byte(name_, offset_, what); }

 private:
  std::span<const uint8_t> bytes_;
  std::string name_;
  size_t offset_ = 0;
};

// Parses a whole token as a finite float (a leading '+' allowed; denormals kept). False otherwise.
bool parse_float(std::string_view token, float& value);

// Appends the shortest decimal text that reads back as exactly `value`.
void append_float(std::string& out, float value);
void append_uint(std::string& out, uint64_t value);
// Appends the little-endian bytes of `value` (the binary writers' byte order).
template <class T>
void append_binary(std::string& out, T value) {
  char raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));
  if constexpr (std::endian::native == std::endian::big) std::reverse(raw, raw + sizeof(T));
  out.append(raw, sizeof(T));
}

// `file` as a path from `folder` (both made absolute first; an empty folder is the current one),
// for a file that refers to another one beside it (an MTL's or PLY's texture, a .gltf's image).
// Empty when there is none (another drive).
std::filesystem::path relative_path(const std::filesystem::path& file, const std::filesystem::path& folder);
// How a file in `folder` names `file`: its relative path where it has one, else the absolute path;
// '/' separated.
std::string path_from(const std::filesystem::path& file, const std::filesystem::path& folder);

// The names an OBJ's usemtl or g statements (and an MTL's newmtl) give the ids `ids` uses, by id:
// `names`' own, printable and told apart, since OBJ knows a material or group by its name alone. An
// empty name is "default"; a name an earlier id took gets "_ID" added (glTF materials may share a
// name or have none). (Defined in obj.cpp.)
std::map<uint32_t, std::string> obj_names(const std::vector<std::string>& names, std::span<const uint32_t> ids);

// Largest polygon a reader accepts before triangulating; a face with a million corners is bad input.
inline constexpr uint64_t max_face_corners = 65536;

// Why a polygon (`what`, e.g. "face 7") with `corners` corners cannot be read; empty when it can.
// Callers test the size first, so the happy path builds no strings.
inline std::string polygon_size_problem(const std::string& what, uint64_t corners) {
  if (corners < 3) return what + " has " + std::to_string(corners) + " vertices, at least 3 are needed";
  if (corners > max_face_corners)
    return what + " has more than the supported " + std::to_string(max_face_corners) + " vertices";
  return {};
}

// Appends the fan triangulation (0, i, i + 1) of a polygon, as every reader triangulates.
template <class Corner>
void append_fan(std::vector<Corner>& triangles, const std::vector<Corner>& polygon) {
  // push_back rather than a range insert, which costs a memmove call per triangle.
  for (size_t i = 1; i + 1 < polygon.size(); ++i) {
    triangles.push_back(polygon[0]);
    triangles.push_back(polygon[i]);
    triangles.push_back(polygon[i + 1]);
  }
}

}  // namespace lod::io
