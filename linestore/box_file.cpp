#include "box_file.h"

#include <zstd.h>

#include <bit>
#include <cstring>
#include <sstream>

#include "error.h"
#include "hash.h"
#include "varint.h"

namespace mpath::linestore {

static_assert(std::endian::native == std::endian::little, "the store is little-endian");

namespace fs = std::filesystem;

namespace {

constexpr char kMagic[8] = {'M', 'P', 'L', 'I', 'N', 'E', 'S', '\0'};
constexpr char kEndMagic[8] = {'M', 'P', 'L', 'S', 'E', 'N', 'D', '\0'};
constexpr size_t kHeaderBytes = 16, kFooterBytes = 40;
constexpr uint64_t kMaxChunkBytes = 1ull << 30;

std::string compress(const std::string& raw, int level) {
  ZSTD_CCtx* cctx = ZSTD_createCCtx();
  ZSTD_CCtx_setParameter(cctx, ZSTD_c_compressionLevel, level);
  ZSTD_CCtx_setParameter(cctx, ZSTD_c_checksumFlag, 1);
  std::string out(ZSTD_compressBound(raw.size()), '\0');
  const size_t n = ZSTD_compress2(cctx, out.data(), out.size(), raw.data(), raw.size());
  ZSTD_freeCCtx(cctx);
  if (ZSTD_isError(n)) throw InputError(fmt::format("zstd compression failed: {}", ZSTD_getErrorName(n)));
  out.resize(n);
  return out;
}

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

std::string encode_lines(const std::vector<LineRecord>& lines, uint64_t& events) {
  ChunkEncoder encoder;
  for (const LineRecord& l : lines) encoder.add(l);
  events = encoder.events();
  return encoder.finish();
}

EncodedChunk compress_chunk(const std::string& raw, uint64_t first_line, uint64_t lines, uint64_t events, int level) {
  EncodedChunk c;
  c.frame = compress(raw, level);
  c.info = {0, c.frame.size(), raw.size(), first_line, lines, events};
  return c;
}

EncodedChunk encode_chunk(const std::vector<LineRecord>& lines, uint64_t first_line, int level) {
  uint64_t events = 0;
  const std::string raw = encode_lines(lines, events);
  return compress_chunk(raw, first_line, lines.size(), events, level);
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

void BoxFileWriter::finish(const std::vector<uint32_t>& face_crossings) {
  std::string counts_raw;
  for (uint32_t c : face_crossings) put_varint(counts_raw, c);
  const std::string counts = compress(counts_raw, 3);
  const uint64_t counts_offset = offset_;
  put(counts.data(), counts.size());

  std::string index;
  append<uint64_t>(index, chunks_.size());
  for (const ChunkInfo& c : chunks_)
    for (uint64_t v : {c.offset, c.bytes, c.raw_bytes, c.first_line, c.lines, c.events}) append(index, v);
  for (uint64_t v : {counts_offset, static_cast<uint64_t>(counts.size()), static_cast<uint64_t>(counts_raw.size()),
                     static_cast<uint64_t>(face_crossings.size())})
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
  const auto faces = take<uint64_t>(index, pos);
  if (counts_raw > kMaxChunkBytes || faces > counts_raw || counts_offset + counts_bytes > index_offset)
    fail("implausible crossing-count sizes in the index");
  const std::string raw = read_frame(counts_offset, counts_bytes, counts_raw, "crossing counts");
  size_t p = 0;
  face_crossings_.resize(faces);
  for (uint64_t f = 0; f < faces; ++f) {
    uint64_t v;
    if (!get_varint(reinterpret_cast<const unsigned char*>(raw.data()), raw.size(), p, v) || v > 0xFFFFFFFFull)
      fail("damaged crossing counts");
    face_crossings_[f] = static_cast<uint32_t>(v);
  }
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

std::string BoxFileReader::read_frame(uint64_t offset, uint64_t bytes, uint64_t raw_bytes, const std::string& what) {
  compressed_.resize(bytes);
  in_.clear();
  in_.seekg(static_cast<std::streamoff>(offset));
  in_.read(compressed_.data(), static_cast<std::streamsize>(bytes));
  if (!in_) fail(fmt::format("{}: truncated", what));
  std::string raw(raw_bytes, '\0');
  const size_t n = ZSTD_decompress(raw.data(), raw.size(), compressed_.data(), compressed_.size());
  if (ZSTD_isError(n)) fail(fmt::format("{}: corrupted ({})", what, ZSTD_getErrorName(n)));
  if (n != raw_bytes) fail(fmt::format("{}: corrupted (size {} instead of {})", what, n, raw_bytes));
  return raw;
}

void BoxFileReader::read_chunk(size_t index, DecodedChunk& out) {
  const ChunkInfo& c = chunks_.at(index);
  raw_ = read_frame(c.offset, c.bytes, c.raw_bytes, fmt::format("chunk {}", index));
  if (!decode_chunk(reinterpret_cast<const unsigned char*>(raw_.data()), raw_.size(), c.lines, out) ||
      out.events.size() != c.events)
    fail(fmt::format("chunk {}: corrupted (records do not decode)", index));
}

}  // namespace mpath::linestore
