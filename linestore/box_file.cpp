#include "box_file.h"

#include <zstd.h>

#include <algorithm>
#include <bit>
#include <cstring>
#include <sstream>

#include "error.h"
#include "hash.h"
#include "prefetch.h"
#include "varint.h"
#include "zstd_frame.h"

namespace mpath::linestore {

static_assert(std::endian::native == std::endian::little, "the store is little-endian");

namespace fs = std::filesystem;

namespace {

constexpr char kMagic[8] = {'M', 'P', 'L', 'I', 'N', 'E', 'S', '\0'};
constexpr char kEndMagic[8] = {'M', 'P', 'L', 'S', 'E', 'N', 'D', '\0'};
constexpr size_t kHeaderBytes = 16, kFooterBytes = 40;
constexpr uint64_t kMaxChunkBytes = 1ull << 30;

template <typename T>
void append(std::string& s, T v) {
  s.append(reinterpret_cast<const char*>(&v), sizeof(T));
}

template <typename T>
T take(const std::string& s, size_t& pos) {
  T v;
  std::memcpy(&v, s.data() + pos, sizeof(T));
  pos += sizeof(T);
  return v;
}

}  // namespace

fs::path partial_path(const fs::path& path) {
  std::string name = ".";
  name += path.filename().string();
  name += ".partial";
  return path.parent_path() / name;
}

std::string encode_lines(const DecodedChunk& lines, const uint32_t* order, uint64_t& events) {
  const size_t n = lines.lines();
  thread_local ChunkEncoder encoder;  // keeps its memory from chunk to chunk
  encoder.reset(n);
  // The lines are taken in `order`, at random in a chunk of megabytes: their
  // events are announced a few lines ahead, or the encoder waits on memory.
  constexpr size_t kAhead = 8;
  for (size_t k = 0; k < n; ++k) {
    if (k + kAhead < n) prefetch(lines.events.data() + lines.first[order[k + kAhead]]);
    const uint32_t i = order[k];
    encoder.add(lines.entry_ar[i], lines.exit_ar[i], lines.events.data() + lines.first[i], lines.first[i + 1] - lines.first[i]);
  }
  events = encoder.events();
  return encoder.finish();
}

EncodedChunk compress_chunk(const std::string& raw, uint64_t first_line, uint64_t lines, uint64_t events, int level) {
  EncodedChunk c;
  c.frame = zstd_compress(raw, level, true);
  c.info = {0, c.frame.size(), raw.size(), first_line, lines, events};
  return c;
}


BoxFileWriter::BoxFileWriter(const fs::path& path, uint32_t box) : file_(path, partial_path(path)), box_(box) {
  put(kMagic, sizeof kMagic);
  put(&kFormatVersion, 4);
  put(&box_, 4);
}

void BoxFileWriter::put(const void* data, size_t size) {
  file_.stream().write(static_cast<const char*>(data), static_cast<std::streamsize>(size));
  if (!file_.stream()) throw InputError(fmt::format("{}: writing failed (disk full?)", file_.temp_path().string()));
  offset_ += size;
}

void BoxFileWriter::write(const EncodedChunk& chunk) {
  ChunkInfo info = chunk.info;
  info.offset = offset_;
  put(chunk.frame.data(), chunk.frame.size());
  chunks_.push_back(info);
}

void BoxCounts::resize(size_t patches, size_t wall_ars, size_t child_ars, size_t class_span) {
  patch_crossings.assign(patches, 0);
  class_crossings.assign(patches * 2 * class_span, 0);
  wall_lines.assign(wall_ars, 0);
  wall_open.assign(wall_ars, 0);
  child_crossings.assign(child_ars, 0);
  associated.assign(wall_ars * kAssociated * 2, 0);
}

void BoxCounts::add_counts(const BoxCounts& o) {
  auto sum = [](std::vector<uint32_t>& a, const std::vector<uint32_t>& b) {
    if (a.size() != b.size()) throw InputError("box counts of different sizes cannot be added");
    for (size_t i = 0; i < a.size(); ++i) a[i] += b[i];
  };
  sum(patch_crossings, o.patch_crossings);
  sum(wall_lines, o.wall_lines);
  sum(wall_open, o.wall_open);
  sum(child_crossings, o.child_crossings);
  sum(class_crossings, o.class_crossings);
}

void BoxCounts::add(const BoxCounts& o) {
  add_counts(o);
  if (associated.size() != o.associated.size()) throw InputError("box counts of different sizes cannot be added");
  std::vector<std::pair<uint64_t, uint32_t>> tallies;
  for (const BoxCounts* c : {static_cast<const BoxCounts*>(this), &o})
    for (size_t i = 0; i < c->associated.size(); i += 2)
      if (c->associated[i] > 0) {
        const uint32_t ar = static_cast<uint32_t>(i / (2 * kAssociated));
        tallies.push_back({associated_key(ar, c->associated[i] - 1), c->associated[i + 1]});
      }
  std::sort(tallies.begin(), tallies.end());
  size_t kept = 0;  // the same (AR, patch) from both: one tally
  for (size_t i = 0; i < tallies.size(); ++i) {
    if (kept > 0 && tallies[kept - 1].first == tallies[i].first) tallies[kept - 1].second += tallies[i].second;
    else tallies[kept++] = tallies[i];
  }
  tallies.resize(kept);
  select_associated(tallies, *this);
}

void select_associated(const std::vector<std::pair<uint64_t, uint32_t>>& tallies, BoxCounts& counts) {
  const size_t ars = counts.wall_lines.size();
  std::vector<std::vector<std::pair<uint32_t, uint32_t>>> per_ar(ars);  // (count, patch)
  for (const auto& [key, n] : tallies) {
    const uint32_t ar = static_cast<uint32_t>(key >> 32);
    if (ar < ars) per_ar[ar].push_back({n, static_cast<uint32_t>(key & 0xFFFFFFFFu)});
  }
  counts.associated.assign(ars * BoxCounts::kAssociated * 2, 0);
  for (size_t ar = 0; ar < ars; ++ar) {
    auto& list = per_ar[ar];
    // Most often met first; equal counts by patch index, so the choice is fixed.
    std::sort(list.begin(), list.end(), [](const auto& a, const auto& b) {
      return a.first != b.first ? a.first > b.first : a.second < b.second;
    });
    for (size_t k = 0; k < std::min(list.size(), BoxCounts::kAssociated); ++k) {
      counts.associated[(ar * BoxCounts::kAssociated + k) * 2] = list[k].second + 1;
      counts.associated[(ar * BoxCounts::kAssociated + k) * 2 + 1] = list[k].first;
    }
  }
}

void BoxFileWriter::finish(const BoxCounts& box_counts) {
  std::string counts_raw;
  const std::vector<uint32_t>* arrays[] = {&box_counts.patch_crossings, &box_counts.wall_lines,
                                           &box_counts.wall_open,       &box_counts.child_crossings,
                                           &box_counts.associated,      &box_counts.class_crossings};
  for (const auto* a : arrays) put_varint(counts_raw, a->size());
  for (const auto* a : arrays)
    for (uint32_t c : *a) put_varint(counts_raw, c);
  const std::string counts = zstd_compress(counts_raw, 3, true);
  const uint64_t counts_offset = offset_;
  put(counts.data(), counts.size());

  std::string index;
  append<uint64_t>(index, chunks_.size());
  for (const ChunkInfo& c : chunks_)
    for (uint64_t v : {c.offset, c.bytes, c.raw_bytes, c.first_line, c.lines, c.events}) append(index, v);
  for (uint64_t v : {counts_offset, static_cast<uint64_t>(counts.size()), static_cast<uint64_t>(counts_raw.size()),
                     uint64_t{0}})
    append(index, v);
  const uint64_t index_offset = offset_;
  put(index.data(), index.size());
  Fnv1a h;
  h.add(index);
  std::string footer;
  for (uint64_t v : {index_offset, static_cast<uint64_t>(index.size()), h.value(), uint64_t{0}}) append(footer, v);
  footer.append(kEndMagic, sizeof kEndMagic);
  put(footer.data(), footer.size());
  file_.commit();
}

BoxFileReader::BoxFileReader(const fs::path& path) : path_(path) {
  if (!fs::exists(path)) fail("missing");
  in_.open(path, std::ios::binary);
  if (!in_) fail("cannot be opened");
  size_ = fs::file_size(path);
  if (size_ < kHeaderBytes + kFooterBytes) fail("truncated (shorter than a header and a footer)");
  std::string header(kHeaderBytes, '\0');
  in_.read(header.data(), kHeaderBytes);
  if (std::memcmp(header.data(), kMagic, sizeof kMagic) != 0) fail("not an mpath line file");
  size_t pos = 8;
  const auto version = take<uint32_t>(header, pos);
  if (version != kFormatVersion)
    fail(fmt::format("store format version {} (this mpath reads version {}; re-run mpath-preprocess)", version,
                     kFormatVersion));
  box_ = take<uint32_t>(header, pos);

  std::string footer(kFooterBytes, '\0');
  in_.seekg(static_cast<std::streamoff>(size_ - kFooterBytes));
  in_.read(footer.data(), kFooterBytes);
  if (std::memcmp(footer.data() + 32, kEndMagic, sizeof kEndMagic) != 0) fail("truncated (no footer at its end)");
  pos = 0;
  const auto index_offset = take<uint64_t>(footer, pos);
  const auto index_bytes = take<uint64_t>(footer, pos);
  const auto index_hash = take<uint64_t>(footer, pos);
  if (index_offset + index_bytes + kFooterBytes != size_) fail("truncated or damaged (index out of place)");
  std::string index(index_bytes, '\0');
  in_.seekg(static_cast<std::streamoff>(index_offset));
  in_.read(index.data(), static_cast<std::streamsize>(index_bytes));
  Fnv1a h;
  h.add(index);
  if (!in_ || h.value() != index_hash) fail("damaged chunk index (checksum mismatch)");
  pos = 0;
  const auto count = take<uint64_t>(index, pos);
  if (index.size() != 8 + count * 48 + 32) fail("damaged chunk index (wrong size)");
  uint64_t expected_line = 0;
  for (uint64_t i = 0; i < count; ++i) {
    ChunkInfo c;
    c.offset = take<uint64_t>(index, pos);
    c.bytes = take<uint64_t>(index, pos);
    c.raw_bytes = take<uint64_t>(index, pos);
    c.first_line = take<uint64_t>(index, pos);
    c.lines = take<uint64_t>(index, pos);
    c.events = take<uint64_t>(index, pos);
    if (c.offset < kHeaderBytes || c.offset + c.bytes > index_offset) fail(fmt::format("chunk {}: out of the file", i));
    // Every line takes at least a byte, every event too; a chunk is well under 1 GiB.
    if (c.raw_bytes > kMaxChunkBytes || c.lines + c.events > c.raw_bytes || c.lines == 0)
      fail(fmt::format("chunk {}: implausible sizes in the index ({} lines, {} events, {} bytes)", i, c.lines, c.events,
                       c.raw_bytes));
    if (i > 0 && c.first_line != expected_line) fail(fmt::format("chunk {}: lines out of sequence", i));
    expected_line = c.first_line + c.lines;
    chunks_.push_back(c);
  }
  const auto counts_offset = take<uint64_t>(index, pos);
  const auto counts_bytes = take<uint64_t>(index, pos);
  const auto counts_raw = take<uint64_t>(index, pos);
  take<uint64_t>(index, pos);  // reserved
  if (counts_raw > kMaxChunkBytes || counts_offset + counts_bytes > index_offset)
    fail("implausible crossing-count sizes in the index");
  std::string raw;
  read_frame(counts_offset, counts_bytes, counts_raw, "crossing counts", raw);
  const auto* bytes = reinterpret_cast<const unsigned char*>(raw.data());
  size_t p = 0;
  std::vector<uint32_t>* arrays[] = {&counts_.patch_crossings, &counts_.wall_lines, &counts_.wall_open,
                                     &counts_.child_crossings, &counts_.associated,  &counts_.class_crossings};
  constexpr int kArrays = static_cast<int>(sizeof arrays / sizeof arrays[0]);
  uint64_t sizes[kArrays];
  for (uint64_t& n : sizes)
    if (!get_varint(bytes, raw.size(), p, n) || n > raw.size()) fail("damaged crossing counts (sizes)");
  for (int a = 0; a < kArrays; ++a) {
    arrays[a]->resize(sizes[a]);
    for (uint32_t& c : *arrays[a]) {
      uint64_t v;
      if (!get_varint(bytes, raw.size(), p, v) || v > 0xFFFFFFFFull) fail("damaged crossing counts");
      c = static_cast<uint32_t>(v);
    }
  }
  if (p != raw.size() || counts_.wall_open.size() != counts_.wall_lines.size() ||
      counts_.associated.size() != counts_.wall_lines.size() * BoxCounts::kAssociated * 2)
    fail("damaged crossing counts (inconsistent sizes)");
}

void BoxFileReader::fail(const std::string& what) const {
  throw InputError(fmt::format("{}: {}", path_.string(), what));
}

uint64_t BoxFileReader::lines() const {
  uint64_t n = 0;
  for (const ChunkInfo& c : chunks_) n += c.lines;
  return n;
}

uint64_t BoxFileReader::events() const {
  uint64_t n = 0;
  for (const ChunkInfo& c : chunks_) n += c.events;
  return n;
}

void BoxFileReader::read_frame(uint64_t offset, uint64_t bytes, uint64_t raw_bytes, const std::string& what,
                               std::string& raw) {
  compressed_.resize(bytes);
  in_.clear();
  in_.seekg(static_cast<std::streamoff>(offset));
  in_.read(compressed_.data(), static_cast<std::streamsize>(bytes));
  if (!in_) fail(fmt::format("{}: truncated", what));
  raw.resize(raw_bytes);  // keeps its memory from chunk to chunk
  if (!dctx_) dctx_.reset(ZSTD_createDCtx());
  if (!dctx_) fail("out of memory for a zstd context");
  const size_t n = ZSTD_decompressDCtx(static_cast<ZSTD_DCtx*>(dctx_.get()), raw.data(), raw.size(), compressed_.data(),
                                       compressed_.size());
  if (ZSTD_isError(n)) fail(fmt::format("{}: corrupted ({})", what, ZSTD_getErrorName(n)));
  if (n != raw_bytes) fail(fmt::format("{}: corrupted (size {} instead of {})", what, n, raw_bytes));
}

void BoxFileReader::FreeDctx::operator()(void* dctx) const { ZSTD_freeDCtx(static_cast<ZSTD_DCtx*>(dctx)); }

BoxFileReader::~BoxFileReader() = default;

void BoxFileReader::read_chunk(size_t index, DecodedChunk& out) {
  const ChunkInfo& c = chunks_.at(index);
  read_frame(c.offset, c.bytes, c.raw_bytes, fmt::format("chunk {}", index), raw_);
  if (!decode_chunk(reinterpret_cast<const unsigned char*>(raw_.data()), raw_.size(), c.lines, c.events, out))
    fail(fmt::format("chunk {}: corrupted (records do not decode)", index));
}

void BoxFileReader::read_chunk_lines(size_t index, const uint32_t* order, size_t take, DecodedChunk& out,
                                     const EventSides* sides) {
  const ChunkInfo& c = chunks_.at(index);
  read_frame(c.offset, c.bytes, c.raw_bytes, fmt::format("chunk {}", index), raw_);
  const auto* data = reinterpret_cast<const unsigned char*>(raw_.data());
  if (!(sides ? decode_chunk_lines(data, raw_.size(), c.lines, c.events, order, take, *sides, place_, out)
              : decode_chunk_lines(data, raw_.size(), c.lines, c.events, order, take, place_, out)))
    fail(fmt::format("chunk {}: corrupted (records do not decode)", index));
}

}  // namespace mpath::linestore
