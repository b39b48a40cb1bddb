#include "directory_lock.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <spdlog/spdlog.h>

#include "error.h"

namespace mpath {

namespace {

// Byte 0 of the lock file is read-locked by readers, byte 1 by shards; a
// writer write-locks both. Readers and shards exclude each other by taking
// their own byte first and then testing the other's, so of two that start
// together at least one sees the other.
struct flock byte_lock(short type, off_t start, off_t length) {
  struct flock l {};
  l.l_type = type;
  l.l_whence = SEEK_SET;
  l.l_start = start;
  l.l_len = length;
  return l;
}

}  // namespace

DirectoryLock::DirectoryLock(const std::filesystem::path& dir, const std::string& name, Role role,
                             const std::string& what, const std::string& advice) {
  const std::filesystem::path path = dir / name;
  fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0) throw InputError(fmt::format("{}: cannot create file: {}", path.string(), std::strerror(errno)));
  struct flock own = role == Role::writer   ? byte_lock(F_WRLCK, 0, 2)
                     : role == Role::reader ? byte_lock(F_RDLCK, 0, 1)
                                            : byte_lock(F_RDLCK, 1, 1);
  struct flock holder = own;
  bool busy = false;
  if (::fcntl(fd_, F_SETLK, &own) != 0) {
    const int err = errno;
    if (err != EACCES && err != EAGAIN) {
      spdlog::warn("{}: cannot lock ({}); two runs on this folder at once would not be told apart", path.string(),
                   std::strerror(err));
      return;
    }
    ::fcntl(fd_, F_GETLK, &holder);  // who holds it, where that can be told
    busy = true;
  } else if (role != Role::writer) {
    holder = byte_lock(F_WRLCK, role == Role::reader ? 1 : 0, 1);  // the other kind's byte
    busy = ::fcntl(fd_, F_GETLK, &holder) == 0 && holder.l_type != F_UNLCK;
  }
  if (!busy) return;
  const bool known = holder.l_type != F_UNLCK && holder.l_pid > 0;
  ::close(fd_);
  fd_ = -1;
  throw InputError(fmt::format("{} {} is in use by another mpath run{}: {}", what, dir.string(),
                               known ? fmt::format(" (process {})", holder.l_pid) : std::string(), advice));
}

DirectoryLock::~DirectoryLock() {
  if (fd_ >= 0) ::close(fd_);  // releases the locks
}

void create_folder(const std::filesystem::path& dir, const std::string& what) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  // (A file in the way is an error here too: "File exists" or "Not a directory".)
  if (ec) throw InputError(fmt::format("{} {}: cannot create the folder: {}", what, dir.string(), ec.message()));
}

}  // namespace mpath
