#include "line_record.h"

#include <cstring>

#include "varint.h"
#include "zstd_frame.h"

namespace mpath::linestore {

namespace {

uint64_t ar_code(uint32_t ar) { return ar == kNoAr ? 0 : static_cast<uint64_t>(ar) + 1; }
uint64_t event_code(const Event& e) {
  return (static_cast<uint64_t>(e.id) << 2) | (static_cast<uint64_t>(e.kind) << 1) | (e.along ? 1 : 0);
}
uint64_t zigzag(int64_t v) { return (static_cast<uint64_t>(v) << 1) ^ static_cast<uint64_t>(v >> 63); }
int64_t unzigzag(uint64_t v) { return static_cast<int64_t>(v >> 1) ^ -static_cast<int64_t>(v & 1); }

}  // namespace

// A chunk is two streams (docs/store-format.md): varint(size of the line
// stream << 1 | steps), the line stream, then the event stream. Line
// stream, per line: varint(events << 1 | has_ars), and if has_ars
// varint(entry + 1), varint(exit + 1). Event stream: per event varint(id <<
// 2 | kind << 1 | along), the first event of a line as a zigzag delta from
// the previous line's first event; with `steps`, each later event's id as a
// zigzag delta from the id before it on its line (varint(zigzag(id -
// previous id) << 2 | kind << 1 | along)); a child box adds varint(entry +
// 1), varint(exit + 1).
void ChunkEncoder::add(uint32_t entry_ar, uint32_t exit_ar, const Event* events, size_t count) {
  const bool has_ars = entry_ar != kNoAr || exit_ar != kNoAr;
  lines_.put((static_cast<uint64_t>(count) << 1) | (has_ars ? 1 : 0));
  if (has_ars) {
    lines_.put(ar_code(entry_ar));
    lines_.put(ar_code(exit_ar));
  }
  for (size_t k = 0; k < count; ++k) {
    const Event& e = events[k];
    const uint64_t code = event_code(e);
    if (k == 0) {
      const uint64_t delta = zigzag(static_cast<int64_t>(code) - static_cast<int64_t>(previous_first_));
      events_.put(delta);
      steps_.put(delta);
      previous_first_ = code;
    } else {
      events_.put(code);
      const int64_t step = static_cast<int64_t>(e.id) - static_cast<int64_t>(events[k - 1].id);
      steps_.put((zigzag(step) << 2) | (code & 3));
    }
    if (e.kind == Event::child_box) {
      for (VarintStream* s : {&events_, &steps_}) {
        s->put(ar_code(e.entry_ar));
        s->put(ar_code(e.exit_ar));
      }
    }
  }
  event_count_ += count;
}

std::string ChunkEncoder::finish() {
  // Crossings after one another on a line are often of one object (the two
  // sides of a desk top, books side by side), and where its patches are
  // numbered together the steps are short (OFFICE: a fifth fewer bytes);
  // where patch numbers follow no such order (office2's) plain ids compress
  // better. A fast zstd level (-1) on a sample of each stream tells which
  // (on the whole streams it cost 3-4 % of OFFICE's preprocess).
  const std::string_view plain = events_.view(), stepped = steps_.view();
  const bool steps = plain != stepped && zstd_sampled_size(stepped, -1) < zstd_sampled_size(plain, -1);
  const std::string_view events = steps ? stepped : plain;
  std::string out;
  out.reserve(10 + lines_.size() + events.size());
  put_varint(out, (static_cast<uint64_t>(lines_.size()) << 1) | (steps ? 1 : 0));
  out += lines_.view();
  out += events;
  return out;
}

void DecodedChunk::clear() {
  first.clear();
  entry_ar.clear();
  exit_ar.clear();
  events.clear();
  foreign_events = false;
}

void gather_lines(const DecodedChunk& from, const uint32_t* order, size_t n, DecodedChunk& out) {
  out.first.resize(n + 1);
  out.entry_ar.resize(n);
  out.exit_ar.resize(n);
  // The lines' sizes first: loads independent of one another, which the core
  // overlaps, where copying line after line would wait for each in turn.
  out.first[0] = 0;
  for (size_t k = 0; k < n; ++k) {
    const uint32_t l = order[k];
    out.first[k + 1] = out.first[k] + (from.first[l + 1] - from.first[l]);
    out.entry_ar[k] = from.entry_ar[l];
    out.exit_ar[k] = from.exit_ar[l];
  }
  out.events.resize(out.first[n]);
  // Lines are a few events long: a plain loop, not a call to memmove per line.
  Event* to = out.events.data();
  for (size_t k = 0; k < n; ++k) {
    const uint32_t l = order[k];
    for (uint32_t e = from.first[l]; e < from.first[l + 1]; ++e) *to++ = from.events[e];
  }
}

namespace {
bool get_ar(const unsigned char* data, size_t size, size_t& pos, uint32_t& ar) {
  uint64_t v;
  if (!get_varint(data, size, pos, v) || v > 0xFFFFFFFFull) return false;
  ar = v == 0 ? kNoAr : static_cast<uint32_t>(v - 1);
  return true;
}
}  // namespace

namespace {

// A chunk's streams: the line stream [line_start, line_end), the event
// stream [line_end, size), and whether later events' ids are steps.
struct Streams {
  size_t line_start = 0, line_end = 0;
  bool steps = false;
};

bool open_streams(const unsigned char* data, size_t size, uint64_t events, Streams& s) {
  size_t pos = 0;
  uint64_t head;
  if (!get_varint(data, size, pos, head)) return false;
  const uint64_t line_bytes = head >> 1;
  // An event is a byte or more; offsets into a chunk's events are 32-bit.
  if (line_bytes > size - pos || events > size - pos - line_bytes || events >= kNoAr) return false;
  s = {pos, pos + line_bytes, (head & 1) != 0};
  return true;
}

// A line's head in the line stream: its event count and wall ARs.
[[gnu::always_inline]] inline bool get_head(const unsigned char* data, size_t line_end, size_t& lp, uint64_t& count,
                                            uint32_t& entry, uint32_t& exit) {
  uint64_t head;
  if (!get_varint(data, line_end, lp, head)) return false;
  entry = exit = kNoAr;
  if ((head & 1) && (!get_ar(data, line_end, lp, entry) || !get_ar(data, line_end, lp, exit))) return false;
  count = head >> 1;
  return true;
}

// The first walk, over the line stream: line i's size and ARs go to place
// place(i) of `out` (kDropped: checked, not kept); then out.first is made
// from the sizes. False unless the stream holds `lines` heads and `events`
// events in all.
constexpr uint32_t kDropped = 0xFFFFFFFFu;

template <typename Place>
bool walk_lines(const unsigned char* data, const Streams& s, uint64_t lines, uint64_t events, size_t kept,
                const Place& place, DecodedChunk& out) {
  // Sized, not cleared: every place is written below, and a buffer kept from
  // chunk to chunk of about the same size then constructs nothing again.
  out.first.resize(kept + 1);
  out.entry_ar.resize(kept);
  out.exit_ar.resize(kept);
  size_t lp = s.line_start;
  uint64_t total = 0;
  for (uint64_t i = 0; i < lines; ++i) {
    uint64_t count;
    uint32_t entry, exit;
    if (!get_head(data, s.line_end, lp, count, entry, exit)) return false;
    total += count;
    if (count > events || total > events) return false;
    const uint32_t k = place(i);
    if (k == kDropped) continue;
    out.first[k + 1] = static_cast<uint32_t>(count);
    out.entry_ar[k] = entry;
    out.exit_ar[k] = exit;
  }
  if (lp != s.line_end || total != events) return false;
  out.first[0] = 0;
  for (size_t k = 0; k < kept; ++k) out.first[k + 1] += out.first[k];
  // A buffer kept from chunk to chunk grows once, with room for a chunk a
  // quarter larger, and without copying what it held: each growth touched
  // memory for the first time (page faults, most of a short solve's system
  // time).
  const uint32_t n = out.first[kept];
  if (out.events.capacity() < n) {
    out.events.clear();
    out.events.reserve(n + n / 4);
  }
  out.events.resize(n);
  return true;
}

// The second walk, over both streams: line i's events are decoded and
// checked, and written from out.events[at(i)] on (at(i) = kDropped: not kept).
template <typename At, typename Kept>
bool walk_events(const unsigned char* data, size_t size, const Streams& s, uint64_t lines, const At& at,
                 const Kept& kept, DecodedChunk& out) {
  size_t lp = s.line_start, ep = s.line_end;
  uint64_t previous_first = 0;
  for (uint64_t i = 0; i < lines; ++i) {
    uint64_t count;
    uint32_t entry, exit;
    get_head(data, s.line_end, lp, count, entry, exit);  // read and checked by walk_lines
    const uint32_t where = at(i);
    Event* to = where == kDropped ? nullptr : out.events.data() + where;
    uint32_t previous_id = 0;
    for (uint64_t j = 0; j < count; ++j) {
      uint64_t code;
      if (!get_varint(data, size, ep, code)) return false;
      int64_t id;
      if (j == 0) {
        code = previous_first + static_cast<uint64_t>(unzigzag(code));  // wraps, never overflows
        previous_first = code;
        id = static_cast<int64_t>(code >> 2);
      } else if (s.steps) {
        id = static_cast<int64_t>(previous_id) + unzigzag(code >> 2);
      } else {
        id = static_cast<int64_t>(code >> 2);
      }
      if (id < 0 || id > 0xFFFFFFFFll) return false;
      previous_id = static_cast<uint32_t>(id);
      Event e;
      e.id = previous_id;
      e.kind = (code & 2) ? Event::child_box : Event::patch;
      e.along = code & 1;
      if (e.kind == Event::child_box && (!get_ar(data, size, ep, e.entry_ar) || !get_ar(data, size, ep, e.exit_ar)))
        return false;
      if (to) {
        kept(e);
        *to++ = e;
      }
    }
  }
  return ep == size;
}

const auto kAsDecoded = [](Event&) {};

}  // namespace

bool decode_chunk(const unsigned char* data, size_t size, uint64_t lines, uint64_t events, DecodedChunk& out) {
  Streams s;
  if (lines > size || !open_streams(data, size, events, s)) return false;  // a line is a byte or more
  const auto same = [](uint64_t i) { return static_cast<uint32_t>(i); };
  return walk_lines(data, s, lines, events, lines, same, out) &&
         walk_events(data, size, s, lines, [&](uint64_t i) { return out.first[i]; }, kAsDecoded, out);
}

namespace {

template <typename Kept>
bool decode_lines_in_order(const unsigned char* data, size_t size, uint64_t lines, uint64_t events,
                           const uint32_t* order, size_t take, const Kept& kept, std::vector<uint32_t>& place,
                           DecodedChunk& out) {
  Streams s;
  if (lines > size || take > lines || !open_streams(data, size, events, s)) return false;
  place.assign(lines, kDropped);
  for (size_t k = 0; k < take; ++k) {
    if (order[k] >= lines || place[order[k]] != kDropped) return false;  // not an order of the chunk's lines
    place[order[k]] = static_cast<uint32_t>(k);
  }
  if (!walk_lines(data, s, lines, events, take, [&](uint64_t i) { return place[i]; }, out)) return false;
  // Each kept line's place becomes where its events go, so that the second
  // walk reads it in line order instead of looking it up at random.
  for (size_t k = 0; k < take; ++k) place[order[k]] = out.first[k];
  return walk_events(data, size, s, lines, [&](uint64_t i) { return place[i]; }, kept, out);
}

}  // namespace

bool decode_chunk_lines(const unsigned char* data, size_t size, uint64_t lines, uint64_t events,
                        const uint32_t* order, size_t take, std::vector<uint32_t>& place, DecodedChunk& out) {
  out.foreign_events = false;
  return decode_lines_in_order(data, size, lines, events, order, take, kAsDecoded, place, out);
}

bool decode_chunk_lines(const unsigned char* data, size_t size, uint64_t lines, uint64_t events,
                        const uint32_t* order, size_t take, const EventSides& sides, std::vector<uint32_t>& place,
                        DecodedChunk& out) {
  out.foreign_events = false;
  const auto* base = static_cast<const unsigned char*>(sides.base);
  bool foreign = false;
  const bool ok = decode_lines_in_order(
      data, size, lines, events, order, take,
      [&](Event& e) {
        if (e.kind != Event::patch || e.id >= sides.count) {
          foreign = true;
          return;
        }
        int f[2];
        std::memcpy(f, base + e.id * sides.stride, sizeof f);
        e.entry_ar = static_cast<uint32_t>(e.along ? f[0] : f[1]);
        e.exit_ar = static_cast<uint32_t>(e.along ? f[1] : f[0]);
      },
      place, out);
  out.foreign_events = foreign;
  return ok;
}

}  // namespace mpath::linestore
