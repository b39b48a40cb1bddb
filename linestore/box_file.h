// One file of stored lines of one box (docs/store-format.md): a header, zstd
// frames of encoded lines (chunks, each with its checksum), a zstd frame of
// crossing counts, and an index that lets readers seek to any chunk.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "atomic_file.h"
#include "line_record.h"

namespace mpath::linestore {

// 3: manifest file hashes by block_hash; 4: class crossings of transparent
// boxes; 5: an event's id after a line's first as a step from the one before
inline constexpr uint32_t kFormatVersion = 5;

// What a box file's lines tell about its box, besides the lines themselves
// (docs/method.md, 6), all counted from the file's lines.
struct BoxCounts {
  static constexpr size_t kAssociated = 4;  // associated patches kept per AR
  std::vector<uint32_t> patch_crossings;    // per patch of the box (its faces are met this often)
  std::vector<uint32_t> wall_lines;         // n_R: line ends at each AR of the box's walls
  std::vector<uint32_t> wall_open;          // n_R^d: of those, lines meeting nothing inside
  std::vector<uint32_t> child_crossings;    // per AR of each child box, in child order
  // Per wall AR, kAssociated (patch + 1, count) pairs: the patches most often
  // met first by lines entering there, most often first (patch + 1 = 0: none).
  std::vector<uint32_t> associated;
  // Transparent boxes (line sets) only: per patch of the box, per side (front,
  // back) and per class the box's lines carry there (`span` of them, its own
  // box's first), the crossings whose next crossing on that side's way is a
  // patch of that class; at class_slot(patch, side, span, class).
  std::vector<uint32_t> class_crossings;

  void resize(size_t patches, size_t wall_ars, size_t child_ars, size_t class_span = 0);
  // Adds the counts of `other` (another shard of the same box); associated
  // patches are merged by their counts.
  void add(const BoxCounts& other);
  // The same for the count arrays alone (not the associated patches).
  void add_counts(const BoxCounts& other);
  bool operator==(const BoxCounts&) const = default;
};

// Where class_crossings holds the count of (patch, side, class) for a box
// whose lines carry `span` classes.
inline size_t class_slot(size_t patch, size_t side, size_t span, size_t cls) { return (patch * 2 + side) * span + cls; }

// Top associated patches from (AR, patch) -> count tallies.
void select_associated(const std::vector<std::pair<uint64_t, uint32_t>>& tallies, BoxCounts& counts);
inline uint64_t associated_key(uint32_t ar, uint32_t patch) { return (uint64_t{ar} << 32) | patch; }

// Where a store file is written before it is complete: a hidden name beside it.
std::filesystem::path partial_path(const std::filesystem::path& path);

struct ChunkInfo {
  uint64_t offset = 0;      // of the zstd frame in the file
  uint64_t bytes = 0;       // compressed
  uint64_t raw_bytes = 0;   // encoded lines before compression
  uint64_t first_line = 0;  // global index of its first line
  uint64_t lines = 0;
  uint64_t events = 0;
};

// An encoded, compressed chunk ready to be written (made in any thread).
struct EncodedChunk {
  std::string frame;  // zstd frame
  ChunkInfo info;     // offset filled in by the writer
};

// Encodes lines order[0 .. n) of `lines` (n = lines.lines()), in that
// order; then compress_chunk makes the frame of lines [first_line,
// first_line + n). Two steps, for callers that time them.
std::string encode_lines(const DecodedChunk& lines, const uint32_t* order, uint64_t& events);
EncodedChunk compress_chunk(const std::string& raw, uint64_t first_line, uint64_t lines, uint64_t events, int level);

// Writes a box file under a temporary name; `finish` renames it into place.
class BoxFileWriter {
 public:
  BoxFileWriter(const std::filesystem::path& path, uint32_t box);
  void write(const EncodedChunk& chunk);
  // The box's counts from the file's lines, then the index; renames.
  void finish(const BoxCounts& counts);

 private:
  void put(const void* data, size_t size);
  AtomicFile file_;
  uint32_t box_;
  uint64_t offset_ = 0;
  std::vector<ChunkInfo> chunks_;
};

// Reads a box file: header, index and counts at open; chunks on demand, each
// decompressed, checksum-verified and decoded. Errors name the file and chunk.
class BoxFileReader {
 public:
  explicit BoxFileReader(const std::filesystem::path& path);
  ~BoxFileReader();
  BoxFileReader(const BoxFileReader&) = delete;
  BoxFileReader& operator=(const BoxFileReader&) = delete;
  uint32_t box() const { return box_; }
  const std::vector<ChunkInfo>& chunks() const { return chunks_; }
  const BoxCounts& counts() const { return counts_; }
  uint64_t lines() const;
  uint64_t events() const;
  void read_chunk(size_t index, DecodedChunk& out);
  // Lines order[0 .. take) of a chunk, in that order (decode_chunk_lines).
  // With `sides`, each kept event's sides written from it (EventSides).
  void read_chunk_lines(size_t index, const uint32_t* order, size_t take, DecodedChunk& out,
                        const EventSides* sides = nullptr);

 private:
  [[noreturn]] void fail(const std::string& what) const;
  void read_frame(uint64_t offset, uint64_t bytes, uint64_t raw_bytes, const std::string& what, std::string& raw);

  std::filesystem::path path_;
  std::ifstream in_;
  uint64_t size_ = 0;
  uint32_t box_ = 0;
  std::vector<ChunkInfo> chunks_;
  BoxCounts counts_;
  std::string compressed_, raw_;
  std::vector<uint32_t> place_;  // scratch of read_chunk_lines
  struct FreeDctx {
    void operator()(void* dctx) const;
  };
  // zstd decompression context, made at the first frame (freed also when the constructor throws).
  std::unique_ptr<void, FreeDctx> dctx_;
};

}  // namespace mpath::linestore
