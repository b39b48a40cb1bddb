// The record of one stored line, in order along the line (docs/method.md, 5):
// the AR of its box's wall where it enters, its events (patch crossings with
// the side facing forward; child-box crossings with entry and exit ARs), and
// the AR where it leaves. The root box's lines have no wall ARs.
#pragma once

#include <cstdint>
#include <cstddef>
#include <string>
#include <vector>

#include "varint.h"

namespace mpath::linestore {

inline constexpr uint32_t kNoAr = 0xFFFFFFFFu;

// 16 bytes (the words first, the flags after them: a pass reads and copies
// millions of these, and the order the fields were once written in made 20).
struct Event {
  enum Kind : uint8_t { patch = 0, child_box = 1 };
  uint32_t id = 0;          // patch index, or child index within the box
  uint32_t entry_ar = kNoAr;  // child box: AR where the line enters it
  uint32_t exit_ar = kNoAr;   // and where it leaves
  Kind kind = patch;
  bool along = false;       // patch: its front faces along the line

  Event() = default;
  Event(Kind kind, uint32_t id, bool along, uint32_t entry_ar = kNoAr, uint32_t exit_ar = kNoAr)
      : id(id), entry_ar(entry_ar), exit_ar(exit_ar), kind(kind), along(along) {}
  bool operator==(const Event&) const = default;
};
static_assert(sizeof(Event) == 16);

struct LineRecord {
  uint32_t entry_ar = kNoAr;
  uint32_t exit_ar = kNoAr;
  std::vector<Event> events;

  bool operator==(const LineRecord&) const = default;
};

// Encodes the lines of one chunk (docs/store-format.md).
class ChunkEncoder {
 public:
  // `lines`: how many lines will be added (to size the streams once).
  explicit ChunkEncoder(size_t lines = 0) { reset(lines); }
  // Empty again, for a chunk of `lines` lines, keeping the streams' memory:
  // an encoder kept from chunk to chunk neither allocates nor touches fresh
  // pages.
  void reset(size_t lines) {
    lines_.clear();
    events_.clear();
    steps_.clear();
    lines_.reserve(lines * 2);
    events_.reserve(lines * 8);
    steps_.reserve(lines * 8);
    previous_first_ = 0;
    event_count_ = 0;
  }
  void add(const LineRecord& line) { add(line.entry_ar, line.exit_ar, line.events.data(), line.events.size()); }
  void add(uint32_t entry_ar, uint32_t exit_ar, const Event* events, size_t count);
  uint64_t events() const { return event_count_; }
  // The chunk, its later events' ids plain or as steps, whichever zstd
  // makes smaller (docs/store-format.md).
  std::string finish();

 private:
  VarintStream lines_;
  VarintStream events_;  // later events' ids plain
  VarintStream steps_;   // later events' ids as steps from the id before
  uint64_t previous_first_ = 0;
  uint64_t event_count_ = 0;
};

// Lines of a decoded chunk, flat: line i's events are events[first[i] .. first[i+1]).
struct DecodedChunk {
  std::vector<uint32_t> first;  // size lines + 1
  std::vector<uint32_t> entry_ar, exit_ar;
  std::vector<Event> events;
  // Decoded with EventSides: some kept event is not a patch of the table's
  // (its sides are left unset).
  bool foreign_events = false;

  size_t lines() const { return first.empty() ? 0 : first.size() - 1; }
  void clear();
};

// Lines order[0 .. n) of `from`, in that order, into `out` (line k of `out`
// is line order[k] of `from`): a traced chunk's lines in stored order
// (TracedChunk::stored). A pass decodes straight into its order instead
// (decode_chunk_lines, tested to give what this gives from the whole chunk).
void gather_lines(const DecodedChunk& from, const uint32_t* order, size_t n, DecodedChunk& out);

// Decodes `lines` records holding `events` events in all from `data`; false
// if the bytes do not hold exactly that.
bool decode_chunk(const unsigned char* data, size_t size, uint64_t lines, uint64_t events, DecodedChunk& out);

// Decodes the chunk as decode_chunk does (every record read and checked) and
// keeps lines order[0 .. take) of it, in that order, as gather_lines would
// from the whole: a pass's lines without a copy of the chunk. `place`:
// scratch. False also when `order` names a line twice or none of the chunk's.
bool decode_chunk_lines(const unsigned char* data, size_t size, uint64_t lines, uint64_t events,
                        const uint32_t* order, size_t take, std::vector<uint32_t>& place, DecodedChunk& out);

// A table of the sides of a box's patches for decode_chunk_lines to write
// into each kept event as it decodes it, where a pass would otherwise go
// over the decoded events again to look them up: record k of `count`, each
// `stride` bytes from `base` on, starts with patch k's two sides {front,
// back} as ints. A patch event's entry_ar then holds the side it turns
// forward along the line (front where `along`), its exit_ar the other; an
// event of a child box, or of a patch past the table, sets
// DecodedChunk::foreign_events.
struct EventSides {
  const void* base = nullptr;
  size_t stride = 0;
  size_t count = 0;
};
bool decode_chunk_lines(const unsigned char* data, size_t size, uint64_t lines, uint64_t events,
                        const uint32_t* order, size_t take, const EventSides& sides, std::vector<uint32_t>& place,
                        DecodedChunk& out);

}  // namespace mpath::linestore
