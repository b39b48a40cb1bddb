// Ray casting with Embree 3 over the patch mesh: nearest hits for local lines
// and camera rays, and every hit along a global line (an intersection filter
// collects them; distances are recomputed in double from the patch planes).
#pragma once

#include <embree3/rtcore.h>

#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "line_hit.h"
#include "mesh.h"

namespace mpath {

// Arrays indexed by traced patch (the tracer's own numbering, LineHit::traced
// or, over every patch, the mesh's) whose entries a caller reads for every
// crossing of a line: all_hits brings each crossing's entry towards the core
// while Embree goes on along the line, instead of the caller waiting for it.
struct HitPrefetch {
  static constexpr int kMax = 3;
  const char* base[kMax] = {};
  size_t stride[kMax] = {};
  int count = 0;
  template <typename T>
  void add(const std::vector<T>& array) {
    if (count < kMax && !array.empty()) {
      base[count] = reinterpret_cast<const char*>(array.data());
      stride[count++] = sizeof(T);
    }
  }
};

struct NearestHit {
  int patch = -1;  // -1: the ray left the scene
  double t = 0;
};

class Tracer {
 public:
  explicit Tracer(const PatchMesh& mesh);
  // Over the patches `subset` of `mesh` only (a box's own patches); hits
  // still name patches by their index in the mesh.
  Tracer(const PatchMesh& mesh, const std::vector<uint32_t>& subset);
  ~Tracer();
  Tracer(const Tracer&) = delete;
  Tracer& operator=(const Tracer&) = delete;

  // Nearest and nearest_from pass the invisible backs of one-sided patches
  // (kInvisibleSide); all_hits reports them (the transports let power pass).
  NearestHit nearest(const Vec3& org, const Vec3& dir, double tnear, double tfar) const;

  // Nearest hit of a line leaving patch `from` at `org` (on the patch). Sees
  // surfaces in contact with the patch (at distance 0, facing it), never the
  // patch itself or coplanar patches facing its way.
  NearestHit nearest_from(int from, const Vec3& org, const Vec3& dir, double tfar) const;

  // Every patch crossed by org + t dir, t in [0, tfar], sorted by distance,
  // with crossings repeated on shared edges of coplanar patches removed.
  // `out` is reused between calls to avoid allocation. The crossings'
  // entries of `prefetch` (if given) are brought towards the core as they are
  // met; the patches' planes and face records always are.
  void all_hits(const Vec3& org, const Vec3& dir, double tfar, std::vector<LineHit>& out,
                const HitPrefetch* prefetch = nullptr) const;


  static std::string embree_version();
  // Crossings closer than this along a line are at one distance (surfaces in contact).
  double tie_epsilon() const { return tie_epsilon_; }
  // Whether some traced patch has an invisible back (docs/scene-formats.md, "Sides").
  bool any_invisible() const { return any_invisible_; }

  // The Embree scene, for benchmarks that measure Embree alone.
  RTCScene embree_scene() const { return scene_; }
  // Per traced patch (LineHit::traced over a subset, LineHit::patch over
  // every patch): PatchMesh::live_face_bits. One byte a patch, where the
  // mesh's face records take eight: read for every crossing, it stays in the
  // caches.
  const uint8_t* live_faces() const { return live_.data(); }
  // Mesh patch of traced patch `local`.
  int global(int local) const { return all_ ? local : static_cast<int>(subset_[local]); }

 private:
  struct Plane {
    Vec3 n;
    double d;  // n . x = d on the plane
  };
  Tracer(const PatchMesh& mesh, const std::vector<uint32_t>& subset, bool all);
  // all_hits' intersection filter: records the hit and lets Embree go on.
  static void collect_filter(const RTCFilterFunctionNArguments* args);
  void add_quads(size_t traced);
  // Distance along the ray to the plane of traced patch `local`, in double precision.
  double plane_distance(int local, const Vec3& org, const Vec3& dir, double fallback) const;

  const PatchMesh& mesh_;
  bool all_ = true;               // every patch of the mesh is traced
  std::vector<uint32_t> subset_;  // otherwise: traced patch -> mesh patch
  std::vector<Plane> planes_;     // per traced patch
  std::vector<uint8_t> live_;     // per traced patch: live_faces()
  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
  double tie_epsilon_ = 0;
  double hair_ = 0;      // a tiny fraction of the scene size
  double near_tie_ = 0;  // hits closer than this get distances in double precision
  bool any_invisible_ = false;  // some traced patch has an invisible back: nearest() passes it
};

// The mesh's Tracer, built at the first get() (from any thread; once): a
// solve that traces nothing (a kept store's first shot read from the store,
// no point lights, cameras or grids, every face carried by stored lines)
// never builds Embree's BVH.
class TracerOnDemand {
 public:
  explicit TracerOnDemand(const PatchMesh& mesh) : mesh_(mesh) {}
  const Tracer& get() const;
  double build_seconds() const { return seconds_; }  // 0 until built

 private:
  const PatchMesh& mesh_;
  mutable std::once_flag once_;
  mutable std::unique_ptr<Tracer> tracer_;
  mutable double seconds_ = 0;
};

}  // namespace mpath
