#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <fstream>
#include <numeric>
#include <random>

#include "box_file.h"
#include "error.h"
#include "hash.h"

#include <cstring>
#include "manifest.h"
#include "radix_sort.h"
#include "test_util.h"
#include "varint.h"
#include "zstd_frame.h"

namespace mpath::linestore {
namespace {

using test::TempDir;

std::vector<LineRecord> random_lines(size_t count, std::mt19937& rng) {
  std::uniform_int_distribution<uint32_t> id(0, 5'000'000), events(0, 12), coin(0, 1), ar(0, 24 * 64 * 6 - 1);
  std::vector<LineRecord> lines(count);
  for (LineRecord& l : lines) {
    if (coin(rng)) {
      l.entry_ar = ar(rng);
      l.exit_ar = ar(rng);
    }
    for (uint32_t k = events(rng); k > 0; --k) {
      Event e;
      e.id = id(rng);
      e.along = coin(rng);
      if (coin(rng) && coin(rng)) {
        e.kind = Event::child_box;
        e.along = false;
        e.entry_ar = ar(rng);
        e.exit_ar = ar(rng);
      }
      l.events.push_back(e);
    }
  }
  return lines;
}

std::vector<LineRecord> records(const DecodedChunk& c) {
  std::vector<LineRecord> out(c.lines());
  for (size_t i = 0; i < c.lines(); ++i) {
    out[i].entry_ar = c.entry_ar[i];
    out[i].exit_ar = c.exit_ar[i];
    out[i].events.assign(c.events.begin() + c.first[i], c.events.begin() + c.first[i + 1]);
  }
  return out;
}

// The lines as one flat set, as the preprocess traces them.
DecodedChunk flat(const std::vector<LineRecord>& lines) {
  DecodedChunk c;
  for (const LineRecord& l : lines) {
    c.first.push_back(static_cast<uint32_t>(c.events.size()));
    c.entry_ar.push_back(l.entry_ar);
    c.exit_ar.push_back(l.exit_ar);
    c.events.insert(c.events.end(), l.events.begin(), l.events.end());
  }
  c.first.push_back(static_cast<uint32_t>(c.events.size()));
  return c;
}

// Writes a file of `chunks` chunks of 1000 random lines; returns the lines.
BoxCounts some_counts(std::vector<uint32_t> patch_crossings) {
  BoxCounts c;
  c.resize(patch_crossings.size(), 3, 2);
  c.patch_crossings = std::move(patch_crossings);
  c.wall_lines = {5, 0, 9};
  c.wall_open = {1, 0, 9};
  c.child_crossings = {3, 4};
  c.associated[0] = 2;  // AR 0: patch 1, met first 4 times
  c.associated[1] = 4;
  return c;
}

std::vector<std::vector<LineRecord>> write_box(const std::filesystem::path& path, int chunks, std::vector<uint32_t> patch_crossings) {
  std::mt19937 rng(42);
  BoxFileWriter writer(path, 3);
  std::vector<std::vector<LineRecord>> all;
  for (int c = 0; c < chunks; ++c) {
    all.push_back(random_lines(1000, rng));
    std::vector<uint32_t> order(all.back().size());
    std::iota(order.begin(), order.end(), 0u);
    uint64_t events = 0;
    const std::string raw = encode_lines(flat(all.back()), order.data(), events);
    writer.write(compress_chunk(raw, 1000ull * c, order.size(), events, 3));
  }
  writer.finish(some_counts(std::move(patch_crossings)));
  return all;
}

TEST(LineStore, RoundTripsRandomLineRecords) {
  TempDir dir;
  const std::vector<uint32_t> counts{0, 7, 4'000'000'000u, 12};
  const auto written = write_box(dir / "box.lines", 4, counts);
  BoxFileReader reader(dir / "box.lines");
  EXPECT_EQ(reader.box(), 3u);
  EXPECT_EQ(reader.lines(), 4000u);
  EXPECT_EQ(reader.counts(), some_counts(counts));
  ASSERT_EQ(reader.chunks().size(), 4u);
  DecodedChunk chunk;
  for (size_t c = 0; c < 4; ++c) {
    EXPECT_EQ(reader.chunks()[c].first_line, 1000 * c);
    reader.read_chunk(c, chunk);
    EXPECT_EQ(records(chunk), written[c]) << "chunk " << c;
  }
  EXPECT_FALSE(std::filesystem::exists(partial_path(dir / "box.lines")));
}

// Chunks of megabytes choose steps or plain ids from zstd's size of a sample
// of each stream: lines along runs of neighbouring ids get steps, lines
// through ids at random get plain ids, as the whole streams' sizes decide.
// The sampled size is exact up to 128 KB and near the whole's beyond.
TEST(LineStore, LongChunksChooseStepsOrPlainIdsAsTheWholeStreamsWould) {
  std::mt19937 rng(11);
  const auto make_lines = [&](bool runs) {
    std::vector<LineRecord> lines(60'000);
    for (LineRecord& l : lines) {
      uint32_t id = std::uniform_int_distribution<uint32_t>(0, 1'000'000)(rng);
      for (int k = std::uniform_int_distribution<int>(2, 8)(rng); k > 0; --k) {
        id = runs ? id + std::uniform_int_distribution<uint32_t>(1, 3)(rng)
                  : std::uniform_int_distribution<uint32_t>(0, 1'000'000)(rng);
        l.events.push_back({Event::patch, id, k % 2 == 0});
      }
    }
    return lines;
  };
  for (const bool runs : {true, false}) {
    const std::vector<LineRecord> lines = make_lines(runs);
    ChunkEncoder fresh(lines.size());
    for (const LineRecord& l : lines) fresh.add(l);
    const std::string raw = fresh.finish();
    EXPECT_GT(raw.size(), size_t{384} << 10);  // thrice the sample
    EXPECT_EQ(raw[0] & 1, runs ? 1 : 0) << "runs " << runs;
    DecodedChunk chunk;
    ASSERT_TRUE(decode_chunk(reinterpret_cast<const unsigned char*>(raw.data()), raw.size(), lines.size(),
                             fresh.events(), chunk));
    EXPECT_EQ(records(chunk), lines);
    // The sampled size against the exact one, on the chunk and on its first 100 KB.
    const double exact = static_cast<double>(zstd_compressed_size(raw, -1));
    EXPECT_NEAR(zstd_sampled_size(raw, -1), exact, 0.1 * exact);
    const std::string_view head(raw.data(), 100'000);
    EXPECT_EQ(zstd_sampled_size(head, -1), static_cast<double>(zstd_compressed_size(head, -1)));
  }
}

// Events after a line's first are stored as plain ids or as steps from the
// id before them, whichever compresses better. The largest and smallest ids
// follow each other both ways and round-trip; lines whose crossings are of
// patches numbered together are stored as steps; a step that leads below 0
// or above the largest id is refused, not wrapped.
TEST(LineStore, IdStepsRoundTripAtTheEndsOfTheRangeAndRefuseLeavingIt) {
  const auto decode = [](const std::string& raw, uint64_t lines, uint64_t events, DecodedChunk& out) {
    return decode_chunk(reinterpret_cast<const unsigned char*>(raw.data()), raw.size(), lines, events, out);
  };
  const uint32_t top = 0xFFFFFFFFu;
  LineRecord line;
  for (const uint32_t id : {top, 0u, top, 5u, 4u, top - 1, 0u})
    line.events.push_back({Event::patch, id, id % 2 == 0});
  LineRecord child = line;
  child.events[2] = {Event::child_box, top, false, 7, kNoAr};
  ChunkEncoder encoder(2);
  encoder.add(line);
  encoder.add(child);
  DecodedChunk chunk;
  ASSERT_TRUE(decode(encoder.finish(), 2, 2 * line.events.size(), chunk));
  EXPECT_EQ(records(chunk), (std::vector<LineRecord>{line, child}));

  // Lines of 2-6 crossings of neighbouring patches among a million.
  std::mt19937 rng(3);
  std::vector<LineRecord> runs(2000);
  ChunkEncoder run_encoder(runs.size());
  for (LineRecord& l : runs) {
    uint32_t id = std::uniform_int_distribution<uint32_t>(0, 1'000'000)(rng);
    for (int k = std::uniform_int_distribution<int>(2, 6)(rng); k > 0; --k)
      l.events.push_back({Event::patch, id += std::uniform_int_distribution<uint32_t>(1, 3)(rng), k % 2 == 0});
    run_encoder.add(l);
  }
  const std::string raw = run_encoder.finish();
  EXPECT_EQ(raw[0] & 1, 1) << "stored as steps";
  ASSERT_TRUE(decode(raw, runs.size(), run_encoder.events(), chunk));
  EXPECT_EQ(records(chunk), runs);

  // One line of two events: id 3, then as a step -3 (zigzag 5: id 0, read),
  // -4 (zigzag 7) or +2^32 (both refused); read plain, each is an id.
  for (const bool steps : {true, false}) {
    for (const uint64_t second : {uint64_t{5}, uint64_t{7}, uint64_t{1} << 33}) {
      std::string one;
      put_varint(one, 1 << 1 | (steps ? 1 : 0));  // a line stream of one byte
      put_varint(one, 2 << 1);                    // two events, no ARs
      put_varint(one, 2 * (3 << 2));              // first event: id 3, zigzag from 0
      put_varint(one, second << 2);
      const bool read = decode(one, 1, 2, chunk);
      EXPECT_EQ(read, steps ? second == 5 : second <= top) << "steps " << steps << ", second " << second;
      if (read) {
        EXPECT_EQ(chunk.events[1].id, steps ? 0u : second);
      }
    }
  }
}

// A pass reads its lines gathered in its own order: line k of the gathered
// chunk is line order[k] of the decoded one, events and ARs alike, for
// orders that repeat no line, take a part of the chunk or none of it.
TEST(LineStore, GatheringLinesKeepsEachLineWhole) {
  TempDir dir;
  const auto written = write_box(dir / "box.lines", 1, {1, 2, 3, 4});
  BoxFileReader reader(dir / "box.lines");
  DecodedChunk chunk, gathered;
  reader.read_chunk(0, chunk);
  std::mt19937 rng(7);
  for (const size_t take : {size_t{0}, size_t{1}, size_t{317}, size_t{1000}}) {
    std::vector<uint32_t> order(chunk.lines());
    std::iota(order.begin(), order.end(), 0u);
    std::shuffle(order.begin(), order.end(), rng);
    gather_lines(chunk, order.data(), take, gathered);
    ASSERT_EQ(gathered.lines(), take);
    const auto lines = records(gathered);
    for (size_t k = 0; k < take; ++k) EXPECT_EQ(lines[k], written[0][order[k]]) << "line " << k;
  }
}

// A pass decodes a chunk straight into its own order (decode_chunk_lines):
// for random chunks (several seeds, lines with and without ARs, child-box
// events), random orders and parts, the lines kept are exactly what
// decoding the whole and gathering in that order gives, one buffer serving
// chunk after chunk of other sizes; an order naming a line twice or a line
// the chunk does not have, or the wrong event count, is refused; and every
// cut of the bytes is refused by both decoders alike.
TEST(LineStore, DecodingIntoPassOrderEqualsDecodingAndGathering) {
  DecodedChunk whole, gathered, direct;
  std::vector<uint32_t> place;
  for (const unsigned seed : {1u, 2u, 3u, 4u, 5u}) {
    std::mt19937 rng(seed);
    const auto lines = random_lines(std::uniform_int_distribution<size_t>(1, 3000)(rng), rng);
    std::vector<uint32_t> identity(lines.size());
    std::iota(identity.begin(), identity.end(), 0u);
    uint64_t events = 0;
    const std::string raw = encode_lines(flat(lines), identity.data(), events);
    const auto* data = reinterpret_cast<const unsigned char*>(raw.data());
    ASSERT_TRUE(decode_chunk(data, raw.size(), lines.size(), events, whole));
    ASSERT_EQ(records(whole), lines);
    for (int trial = 0; trial < 6; ++trial) {
      std::vector<uint32_t> order = identity;
      std::shuffle(order.begin(), order.end(), rng);
      const size_t take = trial == 0 ? lines.size() : trial == 1 ? 0 : std::uniform_int_distribution<size_t>(1, lines.size())(rng);
      gather_lines(whole, order.data(), take, gathered);
      ASSERT_TRUE(decode_chunk_lines(data, raw.size(), lines.size(), events, order.data(), take, place, direct));
      EXPECT_EQ(records(direct), records(gathered)) << "seed " << seed << ", " << take << " lines";
      EXPECT_EQ(direct.first, gathered.first);
    }
    std::vector<uint32_t> order = identity;
    if (lines.size() > 1) {
      order[1] = order[0];
      EXPECT_FALSE(decode_chunk_lines(data, raw.size(), lines.size(), events, order.data(), 2, place, direct));
    }
    order[0] = static_cast<uint32_t>(lines.size());
    EXPECT_FALSE(decode_chunk_lines(data, raw.size(), lines.size(), events, order.data(), 1, place, direct));
    EXPECT_FALSE(decode_chunk_lines(data, raw.size(), lines.size(), events + 1, identity.data(), 1, place, direct));
    EXPECT_FALSE(decode_chunk(data, raw.size(), lines.size(), events + 1, whole));
    if (events > 0) {
      EXPECT_FALSE(decode_chunk(data, raw.size(), lines.size(), events - 1, whole));
    }
    for (size_t cut = 0; cut < raw.size(); cut += 1 + raw.size() / 97) {
      EXPECT_FALSE(decode_chunk(data, cut, lines.size(), events, whole)) << "cut at " << cut;
      EXPECT_FALSE(decode_chunk_lines(data, cut, lines.size(), events, identity.data(), lines.size(), place, direct))
          << "cut at " << cut;
    }
  }
}

// With a table of sides (EventSides: records of 16 bytes, as a pass's box
// keeps them), each kept patch event comes out with the side it turns
// forward along the line in entry_ar and the other in exit_ar, the rest as
// decoded; a kept event of a child box or of a patch past the table marks
// the chunk (foreign_events), one in a line not kept does not.
TEST(LineStore, DecodingWithSidesWritesEachEventsFaces) {
  struct Sides {
    int side[2];
    int other = 7;
    int pad = 0;
  };
  std::mt19937 rng(11);
  std::vector<Sides> table(5'000'001);
  for (size_t k = 0; k < table.size(); ++k) {
    table[k].side[0] = static_cast<int>(k % 1000);
    table[k].side[1] = -1 - static_cast<int>(k % 3);
  }
  DecodedChunk whole, gathered, direct;
  std::vector<uint32_t> place;
  for (int trial = 0; trial < 12; ++trial) {
    auto lines = random_lines(std::uniform_int_distribution<size_t>(1, 2000)(rng), rng);
    for (LineRecord& l : lines)
      for (Event& e : l.events) {
        e.kind = Event::patch;
        e.id %= 4'000'000;  // inside even the cut table
        e.entry_ar = e.exit_ar = kNoAr;
      }
    // A foreign event in the first line: a child box, or a patch past a table cut short.
    const bool child = trial % 3 == 1, cut_table = trial % 3 == 2;
    lines[0].events.push_back(Event(child ? Event::child_box : Event::patch, 4'999'999, false, child ? 3u : kNoAr,
                                    child ? 4u : kNoAr));
    const size_t count = cut_table ? 4'999'999 : table.size();
    std::vector<uint32_t> order(lines.size());
    std::iota(order.begin(), order.end(), 0u);
    uint64_t events = 0;
    const std::string raw = encode_lines(flat(lines), order.data(), events);
    const auto* data = reinterpret_cast<const unsigned char*>(raw.data());
    ASSERT_TRUE(decode_chunk(data, raw.size(), lines.size(), events, whole));
    std::shuffle(order.begin(), order.end(), rng);
    const size_t take = std::uniform_int_distribution<size_t>(1, lines.size())(rng);
    gather_lines(whole, order.data(), take, gathered);
    const EventSides sides{table.data(), sizeof(Sides), count};
    ASSERT_TRUE(decode_chunk_lines(data, raw.size(), lines.size(), events, order.data(), take, sides, place, direct));
    ASSERT_EQ(direct.first, gathered.first);
    bool foreign = false;
    for (size_t i = 0; i < gathered.events.size(); ++i) {
      Event expected = gathered.events[i];
      if (expected.kind != Event::patch || expected.id >= count) {
        foreign = true;
      } else {
        const Sides& t = table[expected.id];
        expected.entry_ar = static_cast<uint32_t>(expected.along ? t.side[0] : t.side[1]);
        expected.exit_ar = static_cast<uint32_t>(expected.along ? t.side[1] : t.side[0]);
      }
      ASSERT_EQ(direct.events[i], expected) << "trial " << trial << ", event " << i;
    }
    EXPECT_EQ(direct.foreign_events, foreign) << "trial " << trial;
    EXPECT_EQ(foreign, trial % 3 != 0 && std::find(order.begin(), order.begin() + take, 0u) != order.begin() + take);
    // Without the table the same chunk decodes as it always did, unmarked.
    ASSERT_TRUE(decode_chunk_lines(data, raw.size(), lines.size(), events, order.data(), take, place, direct));
    EXPECT_EQ(records(direct), records(gathered));
    EXPECT_FALSE(direct.foreign_events);
  }
}

std::string open_error(const std::filesystem::path& path, int chunk = -1) {
  try {
    BoxFileReader reader(path);
    DecodedChunk c;
    for (size_t i = 0; i < reader.chunks().size(); ++i)
      if (chunk < 0 || static_cast<int>(i) == chunk) reader.read_chunk(i, c);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

void patch_file(const std::filesystem::path& path, uint64_t offset, const std::string& bytes) {
  std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
  f.seekp(static_cast<std::streamoff>(offset));
  f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

TEST(LineStore, NamesTheFileAndChunkOfAFlippedByte) {
  TempDir dir;
  write_box(dir / "box.lines", 3, {1, 2});
  const ChunkInfo second = BoxFileReader(dir / "box.lines").chunks()[1];
  std::string byte(1, '\0');
  {
    std::ifstream in(dir / "box.lines", std::ios::binary);
    in.seekg(static_cast<std::streamoff>(second.offset + second.bytes / 2));
    in.read(byte.data(), 1);
  }
  byte[0] = static_cast<char>(byte[0] ^ 0x10);
  patch_file(dir / "box.lines", second.offset + second.bytes / 2, byte);
  const std::string e = open_error(dir / "box.lines");
  EXPECT_NE(e.find("box.lines: chunk 1: corrupted"), std::string::npos) << e;
  EXPECT_EQ(open_error(dir / "box.lines", 0), "");  // the other chunks still read
}

TEST(LineStore, NamesTruncatedForeignAndOtherVersionFiles) {
  TempDir dir;
  write_box(dir / "box.lines", 2, {1});
  const auto size = std::filesystem::file_size(dir / "box.lines");
  std::filesystem::copy_file(dir / "box.lines", dir / "short.lines");
  std::filesystem::resize_file(dir / "short.lines", size - 100);
  EXPECT_NE(open_error(dir / "short.lines").find("short.lines: truncated"), std::string::npos) << open_error(dir / "short.lines");
  std::filesystem::resize_file(dir / "short.lines", 10);
  EXPECT_NE(open_error(dir / "short.lines").find("truncated"), std::string::npos);

  test::write_file(dir / "foreign.lines", std::string(200, 'x'));
  EXPECT_NE(open_error(dir / "foreign.lines").find("not an mpath line file"), std::string::npos);

  std::filesystem::copy_file(dir / "box.lines", dir / "v9.lines");
  patch_file(dir / "v9.lines", 8, std::string("\x09\0\0\0", 4));
  EXPECT_NE(open_error(dir / "v9.lines").find("store format version 9 (this mpath reads version " + std::to_string(kFormatVersion)),
            std::string::npos);
  EXPECT_NE(open_error(dir / "missing.lines").find("missing.lines: missing"), std::string::npos);
}

TEST(LineStore, RefusesAHostileIndexWithImplausibleSizes) {
  TempDir dir;
  write_box(dir / "box.lines", 1, {1, 2});
  // Rewrite the first chunk's raw size to 2^40 and fix the index hash, as a
  // hostile file would: the reader must refuse it, not try to allocate it.
  std::string file = test::read_file(dir / "box.lines");
  uint64_t index_offset, index_bytes;
  std::memcpy(&index_offset, file.data() + file.size() - 40, 8);
  std::memcpy(&index_bytes, file.data() + file.size() - 32, 8);
  const uint64_t huge = 1ull << 40;
  std::memcpy(file.data() + index_offset + 8 + 16, &huge, 8);
  Fnv1a h;
  h.add(file.data() + index_offset, index_bytes);
  const uint64_t hash = h.value();
  std::memcpy(file.data() + file.size() - 24, &hash, 8);
  test::write_file(dir / "box.lines", file);
  EXPECT_NE(open_error(dir / "box.lines").find("chunk 0: implausible sizes"), std::string::npos) << open_error(dir / "box.lines");
}

TEST(BoxCounts, AddingShardsSumsCountsAndMergesAssociatedPatches) {
  BoxCounts a = some_counts({1, 2});
  BoxCounts b = some_counts({10, 20});
  // b: AR 0 meets patch 7 first 9 times, patch 1 once more.
  b.associated[0] = 8;
  b.associated[1] = 9;
  b.associated[2] = 2;
  b.associated[3] = 1;
  a.add(b);
  EXPECT_EQ(a.patch_crossings, (std::vector<uint32_t>{11, 22}));
  EXPECT_EQ(a.wall_lines, (std::vector<uint32_t>{10, 0, 18}));
  EXPECT_EQ(a.child_crossings, (std::vector<uint32_t>{6, 8}));
  // Patch 7 (9 times) before patch 1 (4 + 1 times).
  EXPECT_EQ(std::vector<uint32_t>(a.associated.begin(), a.associated.begin() + 6), (std::vector<uint32_t>{8, 9, 2, 5, 0, 0}));
  BoxCounts wrong;
  wrong.resize(3, 3, 2);
  EXPECT_THROW(a.add(wrong), InputError);
}

TEST(Manifest, RoundTripsAndNamesTheFirstMismatch) {
  TempDir dir;
  Manifest m;
  m.format_version = kFormatVersion;
  m.identity = {{"lines.total", "1000"}, {"mesh.hash", "abc"}};
  m.files.push_back({"box0000.lines", 0, 0, 1000, 2500, 1, 12345, "0123456789abcdef"});
  BoxEntry box;
  box.parent = 0;
  box.depth = 1;
  box.lo[1] = -0.1;
  box.hi[2] = 1.0 / 3.0;
  box.lines = 77;
  box.quotient = 1.25;
  m.boxes = {BoxEntry{}, box};
  write_manifest(dir / "manifest.json", m);
  const Manifest back = read_manifest(dir / "manifest.json");
  EXPECT_EQ(back.identity, m.identity);
  ASSERT_EQ(back.files.size(), 1u);
  EXPECT_EQ(back.files[0].hash, "0123456789abcdef");
  ASSERT_EQ(back.boxes.size(), 2u);
  EXPECT_EQ(back.boxes[1].hi[2], 1.0 / 3.0);  // exactly: the solver compares boxes bit for bit
  EXPECT_EQ(back.boxes[1].lo[1], -0.1);
  EXPECT_EQ(back.boxes[1].lines, 77u);
  EXPECT_EQ(back.boxes[0].parent, -1);
  EXPECT_EQ(identity_mismatch(m.identity, back.identity), "");
  auto other = m.identity;
  other["lines.total"] = "2000";
  EXPECT_EQ(identity_mismatch(other, back.identity), "lines.total: the store was made with 1000, this run has 2000");
  test::write_file(dir / "bad.json", "{\"format_version\": 1");
  EXPECT_THROW(read_manifest(dir / "bad.json"), InputError);
  // A count that is a float, negative or too large is damage, refused by name
  // (found by fuzz/fuzz_manifest: a float was cast to an integer).
  const std::string text = test::read_file(dir / "manifest.json");
  for (const std::string& bad : {std::string("8.4e30"), std::string("-5"), std::string("1.5")}) {
    std::string damaged = text;
    const size_t at = damaged.find("\"lines_total\":");
    ASSERT_NE(at, std::string::npos);
    const size_t from = at + std::string("\"lines_total\":").size();
    damaged.replace(from, damaged.find_first_of(",}", from) - from, bad);
    test::write_file(dir / "damaged.json", damaged);
    try {
      read_manifest(dir / "damaged.json");
      ADD_FAILURE() << bad;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("'lines_total' is"), std::string::npos) << e.what();
    }
  }
  try {
    read_manifest(dir / "none.json");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("run mpath-preprocess"), std::string::npos);
  }
}

// The stored shots' sort of codes: std::sort's order for lists short and
// long, of values spread over every byte, sharing their high bytes, or all
// equal, with the scratch buffer reused from list to list.
TEST(LineStore, RadixSortOfCodesIsStdSortsOrder) {
  std::mt19937 gen(7);
  std::vector<uint32_t> values, scratch;
  for (int trial = 0; trial < 300; ++trial) {
    const size_t n = trial % 5 == 0 ? gen() % 64 : gen() % 5000;
    const uint32_t mask = std::array<uint32_t, 5>{0xffffffffu, 0xffffu, 0xff00ffu, 0x7u, 0u}[trial % 5];
    const uint32_t base = trial % 2 == 0 ? 0u : 0xabcd0000u;
    values.resize(n);
    for (uint32_t& v : values) v = base | (static_cast<uint32_t>(gen()) & mask);
    std::vector<uint32_t> expected = values;
    std::sort(expected.begin(), expected.end());
    sort_u32(values, scratch);
    ASSERT_EQ(values, expected) << trial;
  }
}

}  // namespace
}  // namespace mpath::linestore
