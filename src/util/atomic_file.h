// Files that appear under their final name only when complete: written to a
// temporary name beside the target, checked, then renamed.
#pragma once

#include <filesystem>
#include <fstream>
#include <string>

namespace mpath {

class AtomicFile {
 public:
  explicit AtomicFile(const std::filesystem::path& final_path);
  // The same with a chosen temporary name (beside the final one).
  AtomicFile(const std::filesystem::path& final_path, const std::filesystem::path& temp_path);
  ~AtomicFile();  // removes the temporary file unless committed
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  std::ofstream& stream() { return out_; }
  const std::filesystem::path& temp_path() const { return temp_; }
  // Flushes and renames; throws InputError naming the file if writing failed
  // (a full disk, say).
  void commit();

 private:
  std::filesystem::path final_, temp_;
  std::ofstream out_;
  bool committed_ = false;
  int interrupt_slot_ = -1;
};

// Writes `text` to `path` through an AtomicFile (report.json and the like).
void write_text_file(const std::filesystem::path& path, const std::string& text);

// Temporary name beside `final_path` for writers that need a path (EXR).
std::filesystem::path temporary_path(const std::filesystem::path& final_path);
// Renames a finished temporary file onto its final name, or throws.
void commit_temporary(const std::filesystem::path& temp, const std::filesystem::path& final_path);

}  // namespace mpath
