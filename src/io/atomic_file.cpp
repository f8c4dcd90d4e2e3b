// Atomic file output (atomic_file.h): a temporary file beside the target, flushed, then renamed.
#include "io/atomic_file.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>

#include "nimbus/error.h"

namespace nimbus {

namespace fs = std::filesystem;

void atomic_write(const fs::path& path, const std::function<void(const fs::path& tmp)>& writer) {
  static std::atomic<unsigned> counter{0};
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    throw Error(fmt::format("{}: cannot write: directory '{}' does not exist", path.string(), dir.string()));
  if (fs::is_directory(path, ec)) throw Error(fmt::format("{}: cannot write: is a directory", path.string()));
  const fs::path tmp = dir / fmt::format(".{}.tmp-{}-{}", path.filename().string(), getpid(), counter++);
  try {
    writer(tmp);
  } catch (const Error& e) {
    fs::remove(tmp, ec);
    throw;
  } catch (const std::exception& e) {
    fs::remove(tmp, ec);
    throw Error(fmt::format("{}: cannot write: {}", path.string(), e.what()));
  }
  fs::rename(tmp, path, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw Error(fmt::format("{}: cannot write: {}", path.string(), ec.message()));
  }
}

void atomic_write_bytes(const fs::path& path, const std::string& bytes) {
  atomic_write(path, [&](const fs::path& tmp) {
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) throw Error(fmt::format("{}: cannot write: {}", path.string(), std::strerror(errno)));
    size_t done = 0;
    while (done < bytes.size()) {
      const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        const int err = errno;
        ::close(fd);
        throw Error(fmt::format("{}: cannot write: {}", path.string(), std::strerror(err)));
      }
      done += size_t(n);
    }
    if (::fsync(fd) != 0 && errno != EINVAL) {
      const int err = errno;
      ::close(fd);
      throw Error(fmt::format("{}: cannot write: {}", path.string(), std::strerror(err)));
    }
    if (::close(fd) != 0)
      throw Error(fmt::format("{}: cannot write: {}", path.string(), std::strerror(errno)));
  });
}

}  // namespace nimbus
