// Advisory locks on a folder mpath writes (the store, the outputs), so that
// two runs on one folder are refused by name instead of mixing their files.
#pragma once

#include <filesystem>
#include <string>

namespace mpath {

// The lock file in the store and output folders.
inline constexpr const char* kLockFile = ".mpath.lock";

// Holds POSIX record locks (fcntl) on DIR/NAME for its lifetime; they go
// with the process however it ends, so a killed run leaves none behind.
// Where the file system has no locks (some network mounts) the run goes on
// unlocked, with a warning.
class DirectoryLock {
 public:
  enum class Role {
    writer,  // alone: preprocessing a whole store, writing outputs
    reader,  // with other readers: solving from a store
    shard,   // with other shards: tracing one part of a store
  };
  // Throws InputError when another process holds a lock that conflicts:
  // "`what` DIR is in use by another mpath run (process PID): `advice`".
  DirectoryLock(const std::filesystem::path& dir, const std::string& name, Role role, const std::string& what,
                const std::string& advice);
  ~DirectoryLock();
  DirectoryLock(const DirectoryLock&) = delete;
  DirectoryLock& operator=(const DirectoryLock&) = delete;

 private:
  int fd_ = -1;
};

// Creates `dir` and its parents, or throws InputError naming `what` (the
// config key) and why.
void create_folder(const std::filesystem::path& dir, const std::string& what);

}  // namespace mpath
