#include "lodkit/error.h"

namespace lod {

void throw_bad_input(const std::string& source, const std::string& what) {
  throw Error(ErrorCategory::bad_input, source + ": " + what);
}
void throw_bad_input_at_line(const std::string& source, uint64_t line, const std::string& what) {
  throw Error(ErrorCategory::bad_input, source + ":" + std::to_string(line) + ": " + what);
}
void throw_bad_input_at_byte(const std::string& source, uint64_t byte_offset, const std::string& what) {
  throw Error(ErrorCategory::bad_input, source + ": byte " + std::to_string(byte_offset) + ": " + what);
}
void throw_usage(const std::string& what) { throw Error(ErrorCategory::usage, what); }
void throw_internal(const std::string& what) { throw Error(ErrorCategory::internal, what); }

}  // namespace lod
