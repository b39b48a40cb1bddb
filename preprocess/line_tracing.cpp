#include "line_tracing.h"

#include <algorithm>

#include "line_order.h"

namespace mpath {

namespace {
constexpr unsigned kStoreLineStream = 5;
}

ChunkTracer::ChunkTracer(const Options& options, const PatchMesh& mesh, const Tracer& tracer)
    : mesh_(mesh),
      tracer_(tracer),
      sampler_(line_box(mesh.bounds)),
      sequence_(options.lines.sequence, options.lines.seed, 0),
      seed_(options.lines.seed),
      total_(static_cast<uint64_t>(options.lines.total)),
      chunk_lines_(static_cast<uint64_t>(options.store.chunk_lines)),
      chunks_((total_ + chunk_lines_ - 1) / chunk_lines_) {}

uint64_t ChunkTracer::lines_in(uint64_t chunk) const {
  return std::min(chunk_lines_, total_ - first_line(chunk));
}

void ChunkTracer::trace(uint64_t chunk, std::vector<linestore::LineRecord>& out, std::vector<uint32_t>& crossings) const {
  Rng rng = make_rng(seed_, kStoreLineStream, chunk);
  const uint64_t first = first_line(chunk), n = lines_in(chunk);
  out.resize(n);
  std::vector<LineHit> hits;
  for (uint64_t i = 0; i < n; ++i) {
    double u[4];
    sequence_.point(first + i, rng, u);
    const GlobalLine line = sampler_.sample(u);
    tracer_.all_hits(line.org, line.dir, line.length, hits);
    order_ties(mesh_, tracer_.tie_epsilon(), hits);
    linestore::LineRecord& record = out[i];
    record.events.clear();
    for (const LineHit& h : hits) {
      record.events.push_back({linestore::Event::patch, static_cast<uint32_t>(h.patch), h.along});
      for (int face : mesh_.patch_faces[h.patch])
        if (face >= 0) ++crossings[face];
    }
  }
  // Lines in order of their first and last crossings: neighbouring records
  // start alike, which the delta coding and zstd turn into fewer bytes. Any
  // order of lines is a valid Multipath pass; this one is fixed by the content.
  auto key = [](const linestore::LineRecord& r) {
    if (r.events.empty()) return std::make_pair(uint64_t{0}, uint64_t{0});
    return std::make_pair(uint64_t{r.events.front().id} + 1, uint64_t{r.events.back().id});
  };
  std::stable_sort(out.begin(), out.end(), [&](const auto& a, const auto& b) { return key(a) < key(b); });
}

}  // namespace mpath
