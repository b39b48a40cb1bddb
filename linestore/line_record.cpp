#include "line_record.h"

#include "varint.h"

namespace mpath::linestore {

// A line: varint(events), varint(entry_ar + 1), varint(exit_ar + 1) (0 = none),
// then per event varint(id << 2 | kind << 1 | along), and for a child box
// varint(entry_ar + 1), varint(exit_ar + 1).
void encode_line(const LineRecord& line, std::string& out) {
  put_varint(out, line.events.size());
  put_varint(out, static_cast<uint64_t>(line.entry_ar) + 1);
  put_varint(out, static_cast<uint64_t>(line.exit_ar) + 1);
  for (const Event& e : line.events) {
    put_varint(out, (static_cast<uint64_t>(e.id) << 2) | (static_cast<uint64_t>(e.kind) << 1) | (e.along ? 1 : 0));
    if (e.kind == Event::child_box) {
      put_varint(out, static_cast<uint64_t>(e.entry_ar) + 1);
      put_varint(out, static_cast<uint64_t>(e.exit_ar) + 1);
    }
  }
}

void DecodedChunk::clear() {
  first.clear();
  entry_ar.clear();
  exit_ar.clear();
  events.clear();
}

namespace {
bool get_ar(const unsigned char* data, size_t size, size_t& pos, uint32_t& ar) {
  uint64_t v;
  if (!get_varint(data, size, pos, v) || v > 0x100000000ull) return false;
  ar = static_cast<uint32_t>(v - 1);  // 0 wraps to kNoAr
  return true;
}
}  // namespace

bool decode_chunk(const unsigned char* data, size_t size, uint64_t lines, DecodedChunk& out) {
  out.clear();
  out.first.reserve(lines + 1);
  size_t pos = 0;
  for (uint64_t i = 0; i < lines; ++i) {
    uint64_t count;
    uint32_t entry, exit;
    if (!get_varint(data, size, pos, count) || count > size) return false;
    if (!get_ar(data, size, pos, entry) || !get_ar(data, size, pos, exit)) return false;
    out.first.push_back(static_cast<uint32_t>(out.events.size()));
    out.entry_ar.push_back(entry);
    out.exit_ar.push_back(exit);
    for (uint64_t k = 0; k < count; ++k) {
      uint64_t code;
      if (!get_varint(data, size, pos, code) || (code >> 2) > 0xFFFFFFFFull) return false;
      Event e;
      e.id = static_cast<uint32_t>(code >> 2);
      e.kind = (code & 2) ? Event::child_box : Event::patch;
      e.along = code & 1;
      if (e.kind == Event::child_box && (!get_ar(data, size, pos, e.entry_ar) || !get_ar(data, size, pos, e.exit_ar)))
        return false;
      out.events.push_back(e);
    }
  }
  out.first.push_back(static_cast<uint32_t>(out.events.size()));
  return pos == size;
}

}  // namespace mpath::linestore
