// lodkit: the one exception type the library throws.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>

namespace lod {

enum class ErrorCategory {
  bad_input,  // malformed or unsupported file or data (CLI exit code 2)
  usage,      // invalid options or arguments (CLI exit code 1)
  internal,   // a bug or an unexpected system failure (CLI exit code 3)
};

// Every error message names where the problem is: "file:line: ..." for text formats,
// "file: byte N: ..." for binary ones, so a user can open the file at that place.
class Error : public std::runtime_error {
 public:
  Error(ErrorCategory category, const std::string& message) : std::runtime_error(message), category_(category) {}
  ErrorCategory category() const noexcept { return category_; }

 private:
  ErrorCategory category_;
};

// Helpers that build the conventional message shapes.
[[noreturn]] void throw_bad_input(const std::string& source, const std::string& what);
[[noreturn]] void throw_bad_input_at_line(const std::string& source, uint64_t line, const std::string& what);
[[noreturn]] void throw_bad_input_at_byte(const std::string& source, uint64_t byte_offset, const std::string& what);
[[noreturn]] void throw_usage(const std::string& what);
[[noreturn]] void throw_internal(const std::string& what);

}  // namespace lod
