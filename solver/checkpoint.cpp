#include "checkpoint.h"

#include <cstring>
#include <fstream>

#include "atomic_file.h"
#include "error.h"
#include "hash.h"
#include "store_identity.h"

namespace mpath {

namespace {

constexpr char kMagic[8] = {'M', 'P', 'C', 'K', 'P', 'T', '2', '\0'};

template <typename T>
void put(std::ostream& out, const T& v) {
  out.write(reinterpret_cast<const char*>(&v), sizeof(T));
}

void put_doubles(std::ostream& out, const std::vector<double>& v) {
  put<uint64_t>(out, v.size());
  out.write(reinterpret_cast<const char*>(v.data()), static_cast<std::streamsize>(v.size() * sizeof(double)));
}

class Reader {
 public:
  Reader(const std::filesystem::path& path) : path_(path), in_(path, std::ios::binary) {
    if (!in_) throw InputError(fmt::format("{}: cannot read checkpoint", path.string()));
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
    std::string s(n, '\0');
    if (!in_.read(s.data(), static_cast<std::streamsize>(n))) fail("truncated");
    return s;
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(fmt::format("{}: damaged checkpoint ({}); run without --resume", path_.string(), what));
  }

 private:
  std::filesystem::path path_;
  std::ifstream in_;
};

}  // namespace

std::string checkpoint_key(const Options& options, const PatchMesh& mesh, int threads) {
  Options o = options;
  o.solver.iterations = 0;
  o.solver.tolerance = 0;
  o.output = {};
  o.cameras.clear();
  o.store.zstd_level = 0;
  // Where files live does not change the state (their contents are hashed below);
  // the thread count is added as the effective one.
  o.store.dir.clear();
  o.scene.file.clear();
  o.solver.threads = 0;
  Fnv1a h;
  h.add(options_to_toml(o));
  h.add(hash_file(options.scene.file));
  h.add(mesh_hash(mesh));
  h.add(std::to_string(threads));
  return hex64(h.value());
}

void write_checkpoint(const std::filesystem::path& path, const std::string& key, const RadiosityState& state,
                      const IterationLog& log) {
  AtomicFile file(path);
  std::ostream& out = file.stream();
  out.write(kMagic, sizeof kMagic);
  put<uint64_t>(out, key.size());
  out << key;
  put<uint32_t>(out, static_cast<uint32_t>(state.channels));
  put_doubles(out, state.phi);
  put_doubles(out, state.unshot);
  put_doubles(out, state.ar_in);
  put_doubles(out, state.ar_out);
  put_doubles(out, state.pooled);
  for (const auto* a : {&state.energy.emitted, &state.energy.absorbed, &state.energy.escaped})
    for (double v : *a) put(out, v);
  put(out, log.first_unshot);
  put<uint64_t>(out, log.passes.size());
  for (const PassStats& p : log.passes) {
    put<int32_t>(out, p.pass);
    put(out, p.lines);
    put(out, p.hits);
    put(out, p.seconds);
    put(out, p.unshot_fraction);
  }
  file.commit();
}

void read_checkpoint(const std::filesystem::path& path, const std::string& key, RadiosityState& state,
                     IterationLog& log) {
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
}

}  // namespace mpath
