#include "checkpoint.h"

#include <cmath>
#include <cstring>
#include <fstream>

#include "atomic_file.h"
#include "error.h"
#include "hash.h"

namespace mpath {

namespace {

// 3: the StreamHash of everything before it ends the file.
constexpr char kMagic[8] = {'M', 'P', 'C', 'K', 'P', 'T', '3', '\0'};

class Writer {
 public:
  explicit Writer(std::ostream& out) : out_(out) {}
  void bytes(const void* data, size_t n) {
    out_.write(static_cast<const char*>(data), static_cast<std::streamsize>(n));
    h_.add(data, n);
  }
  template <typename T>
  void put(const T& v) {
    bytes(&v, sizeof(T));
  }
  void put_doubles(const std::vector<double>& v) {
    put<uint64_t>(v.size());
    bytes(v.data(), v.size() * sizeof(double));
  }
  void finish() {
    const uint64_t v = h_.value();
    out_.write(reinterpret_cast<const char*>(&v), sizeof v);
  }

 private:
  std::ostream& out_;
  StreamHash h_;
};

class Reader {
 public:
  // The whole file is checked against its hash before anything is read.
  Reader(const std::filesystem::path& path) : path_(path) {
    std::error_code ec;
    const uint64_t size = std::filesystem::file_size(path, ec);
    if (ec) throw InputError(fmt::format("{}: cannot read checkpoint", path.string()));
    if (size < sizeof(kMagic) + sizeof(uint64_t)) fail("truncated");
    in_.open(path, std::ios::binary);
    if (!in_) throw InputError(fmt::format("{}: cannot read checkpoint", path.string()));
    uint64_t stored = 0;
    in_.seekg(static_cast<std::streamoff>(size - sizeof stored));
    if (!in_.read(reinterpret_cast<char*>(&stored), sizeof stored)) fail("truncated");
    if (hex64(stored) != hash_file(path, size - sizeof stored)) fail("checksum mismatch");
    end_ = size - sizeof stored;
    in_.seekg(0);
  }
  template <typename T>
  T get() {
    T v;
    if (!in_.read(reinterpret_cast<char*>(&v), sizeof(T))) fail("truncated");
    return v;
  }
  void get_doubles(std::vector<double>& v, size_t expected) {
    if (get<uint64_t>() != expected) fail("sizes do not match this scene");
    v.resize(expected);
    if (!in_.read(reinterpret_cast<char*>(v.data()), static_cast<std::streamsize>(expected * sizeof(double)))) fail("truncated");
  }
  std::string get_string(size_t n) {
    if (n > end_) fail("implausible length");
    std::string s(n, '\0');
    if (!in_.read(s.data(), static_cast<std::streamsize>(n))) fail("truncated");
    return s;
  }
  // Everything up to the hash was read.
  void finish() {
    if (static_cast<uint64_t>(in_.tellg()) != end_) fail("its parts do not add up to its size");
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(fmt::format("{}: damaged checkpoint ({}); run without --resume", path_.string(), what));
  }

 private:
  std::filesystem::path path_;
  std::ifstream in_;
  uint64_t end_ = 0;
};

}  // namespace

std::string checkpoint_key(const Options& options, const std::string& geometry) {
  Options o = options;
  o.solver.iterations = 0;
  o.solver.tolerance = 0;
  o.solver.checkpoint_seconds = 0;  // when checkpoints are written, not what they hold
  o.output = {};
  o.cameras.clear();
  o.grids.clear();
  o.store.zstd_level = 0;
  // Where files live does not change the state (their contents are hashed
  // below), nor do threads and ranks (solver.shards fixes the work's parts).
  o.store.dir.clear();
  o.scene.file.clear();
  o.solver.threads = 0;
  Fnv1a h;
  h.add(options_to_toml(o));
  h.add(hash_file(options.scene.file));
  h.add(geometry);
  return hex64(h.value());
}

void write_checkpoint(const std::filesystem::path& path, const std::string& key, const RadiosityState& state,
                      const IterationLog& log) {
  AtomicFile file(path);
  Writer out(file.stream());
  out.bytes(kMagic, sizeof kMagic);
  out.put<uint64_t>(key.size());
  out.bytes(key.data(), key.size());
  out.put<uint32_t>(static_cast<uint32_t>(state.channels));
  out.put_doubles(state.phi);
  out.put_doubles(state.unshot);
  out.put_doubles(state.ar_in);
  out.put_doubles(state.ar_out);
  out.put_doubles(state.pooled);
  for (const auto* a : {&state.energy.emitted, &state.energy.absorbed, &state.energy.escaped})
    for (double v : *a) out.put(v);
  out.put(log.first_unshot);
  out.put<uint64_t>(log.passes.size());
  for (const PassStats& p : log.passes) {
    out.put<int32_t>(p.pass);
    out.put(p.lines);
    out.put(p.hits);
    out.put(p.seconds);
    out.put(p.unshot_fraction);
  }
  out.finish();
  file.commit();
}

void read_checkpoint(const std::filesystem::path& path, const std::string& key, RadiosityState& into,
                     IterationLog& into_log) {
  // Read into copies: the state is replaced only once the whole file checked out.
  RadiosityState state = into;
  IterationLog log = into_log;
  Reader in(path);
  if (in.get_string(sizeof kMagic) != std::string(kMagic, sizeof kMagic)) in.fail("not an mpath checkpoint");
  const auto key_bytes = in.get<uint64_t>();
  if (key_bytes != key.size()) in.fail("unexpected key length");
  const std::string stored = in.get_string(key_bytes);
  if (stored != key)
    throw InputError(fmt::format("{}: made with another scene, store or config (only solver.iterations, "
                                 "solver.tolerance and outputs may change on --resume); run without --resume",
                                 path.string()));
  if (in.get<uint32_t>() != static_cast<uint32_t>(state.channels)) in.fail("channel count differs");
  in.get_doubles(state.phi, state.phi.size());
  in.get_doubles(state.unshot, state.unshot.size());
  in.get_doubles(state.ar_in, state.ar_in.size());
  in.get_doubles(state.ar_out, state.ar_out.size());
  in.get_doubles(state.pooled, state.pooled.size());
  for (auto* a : {&state.energy.emitted, &state.energy.absorbed, &state.energy.escaped})
    for (double& v : *a) v = in.get<double>();
  log.first_unshot = in.get<double>();
  const auto passes = in.get<uint64_t>();
  if (passes > 1'000'000) in.fail("implausible pass count");
  log.passes.clear();
  log.lines = log.hits = 0;
  for (uint64_t i = 0; i < passes; ++i) {
    PassStats p;
    p.pass = in.get<int32_t>();
    p.lines = in.get<uint64_t>();
    p.hits = in.get<uint64_t>();
    p.seconds = in.get<double>();
    p.unshot_fraction = in.get<double>();
    log.passes.push_back(p);
    log.lines += p.lines;
    log.hits += p.hits;
  }
  in.finish();
  for (double v : state.phi)
    if (!std::isfinite(v)) in.fail("a non-finite radiosity");
  into = std::move(state);
  into_log = std::move(log);
}

}  // namespace mpath
