#include "file_read.h"

#include <fcntl.h>
#include <poll.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace multislit::detail {

namespace {

class Descriptor {
 public:
  explicit Descriptor(int fd) : fd_(fd) {}
  ~Descriptor() {
    if (fd_ >= 0) ::close(fd_);
  }
  Descriptor(const Descriptor&) = delete;
  Descriptor& operator=(const Descriptor&) = delete;
  int get() const { return fd_; }

 private:
  int fd_;
};

/// Waits until `fd` has data or is closed by its writer; false when it stayed silent too long.
bool awaitData(int fd, int& silent_ms, const std::string& name) {
  constexpr int kStepMs = 100;
  pollfd p{fd, POLLIN, 0};
  const int ready = ::poll(&p, 1, kStepMs);
  if (ready < 0 && errno == EINTR) throw std::runtime_error(name + ": reading it was interrupted");
  if (ready < 0) throw std::runtime_error(name + " cannot be read: " + std::strerror(errno));
  silent_ms = ready == 0 ? silent_ms + kStepMs : 0;
  return silent_ms < kMaxStreamSilenceMs;
}

}  // namespace

std::string readWholeFile(const std::string& path, const std::string& what, std::size_t max_bytes) {
  const std::string name = what + " '" + path + "'";
  const Descriptor fd(::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC));
  if (fd.get() < 0) throw std::runtime_error(name + " cannot be read: " + std::strerror(errno));
  struct stat status {};
  if (::fstat(fd.get(), &status) != 0)
    throw std::runtime_error(name + " cannot be read: " + std::strerror(errno));
  if (S_ISDIR(status.st_mode)) throw std::runtime_error(name + " is a folder, not a file");
  const bool regular = S_ISREG(status.st_mode);
  const std::string limit = "more than the limit of " + std::to_string(max_bytes) + " bytes";
  if (regular && static_cast<std::size_t>(status.st_size) > max_bytes)
    throw std::runtime_error(name + " is " + std::to_string(status.st_size) + " bytes, " + limit);
  std::string text;
  char chunk[1 << 16];
  for (int silent_ms = 0;;) {
    const ssize_t n = ::read(fd.get(), chunk, sizeof chunk);
    if (n == 0) break;
    if (n > 0) {
      text.append(chunk, static_cast<std::size_t>(n));
      if (text.size() > max_bytes) throw std::runtime_error(name + " holds " + limit);
    } else if (errno == EAGAIN || errno == EWOULDBLOCK) {
      if (!awaitData(fd.get(), silent_ms, name))
        throw std::runtime_error(name + " sent nothing for " +
                                 std::to_string(kMaxStreamSilenceMs / 1000) + " s");
    } else if (errno == EINTR) {
      throw std::runtime_error(name + ": reading it was interrupted");
    } else {
      throw std::runtime_error(name + " cannot be read: " + std::strerror(errno));
    }
  }
  if (!regular && text.empty())
    throw std::runtime_error(name +
                             " is a pipe or device that gave nothing (a FIFO nobody "
                             "writes to?)");
  return text;
}

}  // namespace multislit::detail
