// Atomic output: write a temporary file beside the target, flush it to disk, then rename, so a crash
// or a full disk never leaves a partial output and readers never see a half-written file.
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <random>
#include <utility>

#include "lodkit/error.h"
#include "lodkit/io.h"

namespace lod {

namespace {
std::string errno_text() { return std::strerror(errno); }
}  // namespace

FileBytes read_file_bytes(const std::filesystem::path& path) {
  const std::string name = path.string();
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw_bad_input(name, "is a directory, expected a mesh file");
  int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw_bad_input(name, "cannot open: " + errno_text());
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    throw_bad_input(name, "not a regular file");
  }
  FileBytes file;
  file.size_ = size_t(st.st_size);
  if (file.size_ > 0) {
    void* p = ::mmap(nullptr, file.size_, PROT_READ, MAP_PRIVATE, fd, 0);
    if (p != MAP_FAILED) {
      ::madvise(p, file.size_, MADV_SEQUENTIAL);  // readers walk the file front to back
      file.data_ = static_cast<const uint8_t*>(p);
      file.mapped_ = true;
    }
  }
  if (!file.mapped_ && file.size_ > 0) {
    file.copy_.resize(file.size_);
    size_t done = 0;
    while (done < file.size_) {
      ssize_t n = ::read(fd, file.copy_.data() + done, file.size_ - done);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        ::close(fd);
        throw_bad_input(name, "read failed at byte " + std::to_string(done) + ": " + (n < 0 ? errno_text() : "file shrank"));
      }
      done += size_t(n);
    }
    file.data_ = file.copy_.data();
  }
  ::close(fd);
  return file;
}

FileBytes::~FileBytes() {
  if (mapped_) ::munmap(const_cast<uint8_t*>(data_), size_);
}

FileBytes::FileBytes(FileBytes&& other) noexcept { *this = std::move(other); }

FileBytes& FileBytes::operator=(FileBytes&& other) noexcept {
  if (this == &other) return *this;
  if (mapped_) ::munmap(const_cast<uint8_t*>(data_), size_);
  mapped_ = std::exchange(other.mapped_, false);
  size_ = std::exchange(other.size_, 0);
  copy_ = std::move(other.copy_);
  data_ = mapped_ ? other.data_ : copy_.data();
  other.data_ = nullptr;
  return *this;
}

void write_file_atomic(const std::filesystem::path& path, std::span<const uint8_t> bytes) {
  const std::filesystem::path dir = path.has_parent_path() ? path.parent_path() : std::filesystem::path(".");
  // Built by appends: GCC 12 warns falsely (-Wrestrict) on "." + std::string&&.
  std::string hidden = ".";
  hidden += path.filename().string();
  hidden += ".tmp.XXXXXX";
  std::string tmpl = (dir / hidden).string();
  int fd = ::mkstemp(tmpl.data());
  if (fd < 0) throw_bad_input(path.string(), "cannot create a temporary file in " + dir.string() + ": " + errno_text());
  size_t done = 0;
  while (done < bytes.size()) {
    ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      std::string why = errno_text();
      ::close(fd);
      ::unlink(tmpl.c_str());
      throw_bad_input(path.string(), "write failed: " + why);
    }
    done += size_t(n);
  }
  ::fchmod(fd, 0644);
  if (::fsync(fd) != 0 || ::close(fd) != 0) {
    std::string why = errno_text();
    ::unlink(tmpl.c_str());
    throw_bad_input(path.string(), "write failed: " + why);
  }
  if (::rename(tmpl.c_str(), path.c_str()) != 0) {
    std::string why = errno_text();
    ::unlink(tmpl.c_str());
    throw_bad_input(path.string(), "cannot rename temporary file into place: " + why);
  }
}

void write_file_atomic(const std::filesystem::path& path, const std::string& bytes) {
  write_file_atomic(path, std::span<const uint8_t>(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size()));
}

}  // namespace lod
