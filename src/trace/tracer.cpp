#include "tracer.h"

#include <chrono>

#include <algorithm>
#include <cmath>

#include "error.h"
#include "prefetch.h"

namespace mpath {
namespace {

// The intersect context of an all-hits query: Embree hands it to the filter.
struct CollectContext {
  RTCIntersectContext context;
  std::vector<LineHit>* hits;
  const Tracer* tracer;
  const HitPrefetch* prefetch;
};

// Whether a hit is on the invisible back of a one-sided patch: a ray passes it.
bool passes(const RTCFilterFunctionNArguments* args, const Tracer& tracer, const PatchMesh& mesh, int prim) {
  const int patch = tracer.global(prim);
  if (mesh.patch_faces[patch][1] != kInvisibleSide) return false;
  const Vec3 dir{RTCRayN_dir_x(args->ray, args->N, 0), RTCRayN_dir_y(args->ray, args->N, 0),
                 RTCRayN_dir_z(args->ray, args->N, 0)};
  return mesh.side_met(patch, dir) == 1;
}

// The intersect context of a nearest query in a scene with invisible backs.
struct NearestContext {
  RTCIntersectContext context;
  const PatchMesh* mesh;
  const Tracer* tracer;
};

void nearest_filter(const RTCFilterFunctionNArguments* args) {
  auto* ctx = reinterpret_cast<NearestContext*>(args->context);
  if (passes(args, *ctx->tracer, *ctx->mesh, static_cast<int>(RTCHitN_primID(args->hit, args->N, 0))))
    args->valid[0] = 0;
}

void sort_by_distance(LineHit* hits, size_t n) {
  // Few hits per line: insertion sort beats std::sort here.
  for (size_t i = 1; i < n; ++i) {
    const LineHit h = hits[i];
    size_t j = i;
    while (j > 0 && (hits[j - 1].t > h.t || (hits[j - 1].t == h.t && hits[j - 1].patch > h.patch))) {
      hits[j] = hits[j - 1];
      --j;
    }
    hits[j] = h;
  }
}

// The intersect context of a nearest_from query.
struct LeaveContext {
  RTCIntersectContext context;
  const PatchMesh* mesh;
  const Tracer* tracer;
  int from;  // traced patch
  double behind;   // distances below this are behind the start point: never met
  double contact;  // distances below this are contacts with the start plane
  double self;     // distances below this to the patch's own object are float rounding, not a surface met
};

void leave_filter(const RTCFilterFunctionNArguments* args) {
  auto* ctx = reinterpret_cast<LeaveContext*>(args->context);
  const int prim = static_cast<int>(RTCHitN_primID(args->hit, args->N, 0));
  const float t = RTCRayN_tfar(args->ray, args->N, 0);
  if (prim == ctx->from || passes(args, *ctx->tracer, *ctx->mesh, prim)) {
    args->valid[0] = 0;
    return;
  }
  if (t < ctx->behind) {  // between the hair's start and the patch: behind where the line leaves
    args->valid[0] = 0;
    return;
  }
  const auto& patches = ctx->mesh->patches;
  const int a = ctx->tracer->global(prim);
  const int b = ctx->tracer->global(ctx->from);
  if (t <= ctx->contact && dot(patches[a].normal, patches[b].normal) > 0) args->valid[0] = 0;
  // A line that leaves a patch within float rounding of an edge of its own
  // object can be placed just outside the neighbouring face and meet it at
  // once: a surface that close is the object itself, not something lit.
  else if (t <= ctx->self && patches[a].object == patches[b].object) args->valid[0] = 0;
}

void embree_error(void*, RTCError code, const char* message) {
  if (code != RTC_ERROR_NONE) fmt::print(stderr, "mpath: embree error {}: {}\n", static_cast<int>(code), message ? message : "");
}

void init_ray(RTCRayHit& rh, const Vec3& org, const Vec3& dir, double tnear, double tfar) {
  rh.ray.org_x = static_cast<float>(org.x);
  rh.ray.org_y = static_cast<float>(org.y);
  rh.ray.org_z = static_cast<float>(org.z);
  rh.ray.dir_x = static_cast<float>(dir.x);
  rh.ray.dir_y = static_cast<float>(dir.y);
  rh.ray.dir_z = static_cast<float>(dir.z);
  rh.ray.tnear = static_cast<float>(tnear);
  rh.ray.tfar = static_cast<float>(tfar);
  rh.ray.time = 0;
  rh.ray.mask = 0xFFFFFFFFu;
  rh.ray.id = 0;
  rh.ray.flags = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
}

}  // namespace

Tracer::Tracer(const PatchMesh& mesh) : Tracer(mesh, {}, true) {}

Tracer::Tracer(const PatchMesh& mesh, const std::vector<uint32_t>& subset) : Tracer(mesh, subset, false) {}

Tracer::Tracer(const PatchMesh& mesh, const std::vector<uint32_t>& subset, bool all)
    : mesh_(mesh), all_(all), subset_(subset) {
  const size_t traced = all_ ? mesh.patches.size() : subset_.size();
  planes_.reserve(traced);
  live_.reserve(traced);
  for (size_t i = 0; i < traced; ++i) {
    const Patch& p = mesh.patches[global(static_cast<int>(i))];
    planes_.push_back({p.normal, dot(p.normal, mesh.vertices[p.v[0]])});
    live_.push_back(mesh.live_face_bits(global(static_cast<int>(i))));
    any_invisible_ |= mesh.patch_faces[global(static_cast<int>(i))][1] == kInvisibleSide;
  }
  device_ = rtcNewDevice("verbose=0");
  MPATH_CHECK(device_ != nullptr, "rtcNewDevice failed (error {})", static_cast<int>(rtcGetDeviceError(nullptr)));
  rtcSetDeviceErrorFunction(device_, embree_error, nullptr);
  scene_ = rtcNewScene(device_);
  rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION);
  rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_HIGH);

  if (traced > 0) add_quads(traced);
  rtcCommitScene(scene_);
  MPATH_CHECK(rtcGetDeviceError(device_) == RTC_ERROR_NONE, "embree scene build failed");
  tie_epsilon_ = 1e-7 * std::max(mesh.bounds.diagonal(), 1e-30);
  near_tie_ = 1e-4 * std::max(mesh.bounds.diagonal(), 1e-30);
  hair_ = 1e-6 * std::max(mesh.bounds.diagonal(), 1e-30);
}

void Tracer::add_quads(size_t traced) {
  const PatchMesh& mesh = mesh_;
  RTCGeometry geom = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_QUAD);
  auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                         3 * sizeof(float), mesh.vertices.size()));
  for (size_t i = 0; i < mesh.vertices.size(); ++i)
    for (int k = 0; k < 3; ++k) vb[3 * i + k] = static_cast<float>(mesh.vertices[i][k]);
  auto* ib = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT4,
                                                            4 * sizeof(unsigned), traced));
  for (size_t i = 0; i < traced; ++i)
    for (int k = 0; k < 4; ++k) ib[4 * i + k] = mesh.patches[global(static_cast<int>(i))].v[k];
  rtcCommitGeometry(geom);
  rtcAttachGeometry(scene_, geom);
  rtcReleaseGeometry(geom);
}

Tracer::~Tracer() {
  if (scene_) rtcReleaseScene(scene_);
  if (device_) rtcReleaseDevice(device_);
}

std::string Tracer::embree_version() {
  return fmt::format("{}.{}.{}", RTC_VERSION_MAJOR, RTC_VERSION_MINOR, RTC_VERSION_PATCH);
}

NearestHit Tracer::nearest(const Vec3& org, const Vec3& dir, double tnear, double tfar) const {
  NearestContext ctx;
  rtcInitIntersectContext(&ctx.context);
  if (any_invisible_) ctx.context.filter = nearest_filter;
  ctx.mesh = &mesh_;
  ctx.tracer = this;
  RTCRayHit rh;
  init_ray(rh, org, dir, tnear, tfar);
  rtcIntersect1(scene_, &ctx.context, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return {};
  const int local = static_cast<int>(rh.hit.primID);
  return {global(local), plane_distance(local, org, dir, rh.ray.tfar)};
}

NearestHit Tracer::nearest_from(int from, const Vec3& org, const Vec3& dir, double tfar) const {
  if (!all_) {  // `from` in traced numbering
    const auto it = std::lower_bound(subset_.begin(), subset_.end(), static_cast<uint32_t>(from));
    MPATH_CHECK(it != subset_.end() && *it == static_cast<uint32_t>(from), "nearest_from: patch {} is not traced", from);
    from = static_cast<int>(it - subset_.begin());
  }
  // Start a hair behind the patch so that a surface touching it is met.
  LeaveContext ctx;
  rtcInitIntersectContext(&ctx.context);
  ctx.context.filter = leave_filter;
  ctx.mesh = &mesh_;
  ctx.tracer = this;
  ctx.from = from;
  // The hair is the scene's 1e-6, but no more than a thousandth of the
  // patch's size (a millimetre patch in a kilometre scene must not start
  // its lines on its far side), and no less than a few float steps at the
  // patch's place (where single precision can still tell the two apart).
  const double size = std::sqrt(mesh_.patches[global(from)].area);
  const double magnitude = std::max({std::fabs(org.x), std::fabs(org.y), std::fabs(org.z), 1e-30});
  const double step = magnitude * 0x1p-23;  // float spacing near |org|
  const double hair = std::max(4.0 * step, std::min(hair_, 1e-3 * size));
  ctx.behind = hair - 2.0 * step;  // >= hair / 2: contacts within two float steps of the patch still count
  ctx.contact = 2.0 * hair;
  ctx.self = hair + 16.0 * step;
  const Vec3 start = org - dir * hair;
  RTCRayHit rh;
  init_ray(rh, start, dir, 0.0, tfar);
  rtcIntersect1(scene_, &ctx.context, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return {};
  const int local = static_cast<int>(rh.hit.primID);
  return {global(local), std::max(0.0, plane_distance(local, start, dir, rh.ray.tfar) - hair)};
}

void Tracer::collect_filter(const RTCFilterFunctionNArguments* args) {
  auto* ctx = reinterpret_cast<CollectContext*>(args->context);
  const float t = RTCRayN_tfar(args->ray, args->N, 0);
  const unsigned prim = RTCHitN_primID(args->hit, args->N, 0);
  // Embree's geometric normal has the orientation of the patch's corners.
  const float facing = RTCHitN_Ng_x(args->hit, args->N, 0) * RTCRayN_dir_x(args->ray, args->N, 0) +
                       RTCHitN_Ng_y(args->hit, args->N, 0) * RTCRayN_dir_y(args->ray, args->N, 0) +
                       RTCHitN_Ng_z(args->hit, args->N, 0) * RTCRayN_dir_z(args->ray, args->N, 0);
  ctx->hits->push_back({static_cast<double>(t), static_cast<int>(prim), facing > 0});
  // What the line's crossings are read with next (the planes where crossings
  // come close, the faces, the caller's arrays) is chosen at random among the
  // patches: ask for it now, while Embree goes on along the line.
  const Tracer& tracer = *ctx->tracer;
  prefetch_l2(&tracer.planes_[prim]);
  prefetch_l2(&tracer.live_[prim]);
  // (Over a subset, the mesh's face records' place is known only after a
  // load of the subset's entry: waiting for it here made the preprocess 5 %
  // slower. Its callers read live_faces() instead.)
  if (tracer.all_) {
    prefetch_l2(&tracer.mesh_.patch_faces[prim]);
  } else {
    prefetch_l2(&tracer.subset_[prim]);
  }
  if (const HitPrefetch* p = ctx->prefetch)
    for (int k = 0; k < p->count; ++k) prefetch_l2(p->base[k] + p->stride[k] * prim);
  args->valid[0] = 0;  // reject, so traversal goes on to the next hit
}

double Tracer::plane_distance(int local, const Vec3& org, const Vec3& dir, double fallback) const {
  const Plane& p = planes_[local];
  const double denom = dot(p.n, dir);
  if (std::fabs(denom) < 1e-12) return fallback;
  return (p.d - dot(p.n, org)) / denom;
}

void Tracer::all_hits(const Vec3& org, const Vec3& dir, double tfar, std::vector<LineHit>& out,
                      const HitPrefetch* prefetch) const {
  out.clear();
  CollectContext ctx;
  rtcInitIntersectContext(&ctx.context);
  ctx.context.filter = collect_filter;
  ctx.hits = &out;
  ctx.tracer = this;
  ctx.prefetch = prefetch;
  RTCRayHit rh;
  init_ray(rh, org, dir, 0.0, tfar);
  rtcIntersect1(scene_, &ctx.context, &rh);
  sort_by_distance(out.data(), out.size());
  // Where hits come close (surfaces in contact, shared edges), Embree's
  // single-precision distances cannot order them: recompute those in double
  // from the patch planes, so that coplanar patches get equal distances.
  for (size_t i = 0; i + 1 < out.size();) {
    size_t j = i + 1;
    while (j < out.size() && out[j].t - out[j - 1].t <= near_tie_) ++j;
    if (j - i > 1) {
      for (size_t k = i; k < j; ++k) out[k].t = plane_distance(out[k].patch, org, dir, out[k].t);
      sort_by_distance(out.data() + i, j - i);
    }
    i = j;
  }
  // The same patch twice (a quad's diagonal), or coplanar patches facing the
  // same way at one distance (a shared edge): one crossing.
  size_t kept = 0;
  for (size_t i = 0; i < out.size(); ++i) {
    bool duplicate = false;
    for (size_t j = kept; j-- > 0 && out[i].t - out[j].t <= tie_epsilon_;) {
      if (out[i].patch == out[j].patch || dot(planes_[out[i].patch].n, planes_[out[j].patch].n) > 1.0 - 1e-9) {
        duplicate = true;
        break;
      }
    }
    if (!duplicate) out[kept++] = out[i];
  }
  out.resize(kept);
  if (!all_)
    for (LineHit& h : out) {
      h.traced = h.patch;
      h.patch = global(h.patch);
    }
}

const Tracer& TracerOnDemand::get() const {
  std::call_once(once_, [this] {
    const auto start = std::chrono::steady_clock::now();
    tracer_ = std::make_unique<Tracer>(mesh_);
    seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  });
  return *tracer_;
}

}  // namespace mpath
