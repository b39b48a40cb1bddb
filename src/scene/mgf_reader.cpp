// MGF reader (Materials and Geometry Format, Ward 1995) covering what
// RenderPark scenes use: c/cxy/cspec/cct/cmix colours, m/rd/ed/sides
// materials (other material entities only affect specular transport and are
// skipped), o objects, xf transforms (with -i and -a), i includes, v/p/n
// vertices, f faces and the curved primitives, tessellated.
// Colours follow docs/colour.md; `ed` (lm/m2) becomes W/m2 at 179 lm/W.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <map>
#include <numbers>
#include <set>

#include "color.h"
#include "error.h"
#include "text_tokenizer.h"
#include "scene_readers.h"
#include "tessellate.h"
#include "transform.h"

namespace mpath {
namespace {

namespace fs = std::filesystem;

struct MgfMaterial {
  double rd = 0.0;
  Chromaticity rd_color;
  double ed = 0.0;
  Chromaticity ed_color;
  int sides = 1;
};

struct MgfVertex {
  Vec3 p;
  Vec3 n;
};

// A scene larger than this is almost surely a mistake (or hostile).
constexpr size_t kMaxPolygons = 20'000'000;
constexpr size_t kMaxIncludeReads = 100'000;
constexpr size_t kMaxObjectDepth = 256;

struct Entry {
  std::vector<std::string> t;
  long line = 0;
};

// A line the reader skips with a warning (as the reference parser goes on
// after an unknown entity): malformed arguments, undefined names. Limits and
// unreadable files stay errors.
class SkippedLine : public InputError {
 public:
  explicit SkippedLine(const InputError& e) : InputError(e.what()) {}
};

struct XfFrame {
  Transform total;       // transform in force inside this context
  size_t body_start = 0; // first entry after the xf line (for arrays)
  int file = -1;         // the file that opened the context
  std::vector<std::string> args;
  std::vector<int> counts, index;  // array sizes and the current element
};

class MgfReader {
 public:
  MgfReader(Scene& scene, int curve_segments, int default_sides)
      : scene_(scene), segments_(curve_segments), default_sides_(default_sides) {
    unnamed_material_.sides = default_sides;
    current_material_ = &unnamed_material_;
    current_color_ = &unnamed_color_;
  }

  void read_file(const fs::path& path, int depth) {
    if (depth > 32) throw InputError(fmt::format("{}: includes nested more than 32 deep", path.string()));
    std::vector<Entry> entries;
    {
      TextTokenizer in(path);
      std::vector<std::string_view> tokens;
      while (in.next(tokens)) entries.push_back({std::vector<std::string>(tokens.begin(), tokens.end()), in.line()});
    }
    const size_t xf_depth = xf_.size();
    const int saved_file = file_;
    file_ = ++files_read_;
    path_ = path.string();
    for (size_t i = 0; i < entries.size(); ++i) {
      line_ = entries[i].line;
      try {
        i = execute(entries[i].t, path, i, depth);
      } catch (const SkippedLine& e) {
        if (skipped_++ < kSkippedShown) skipped_lines_.push_back(e.what());
      }
      path_ = path.string();
    }
    if (xf_.size() > xf_depth) {
      if (skipped_++ < kSkippedShown)
        skipped_lines_.push_back(fmt::format("{}: 'xf' context left open at end of file (closed there)", path_));
      xf_.resize(xf_depth);
    }
    file_ = saved_file;
  }

  // What was skipped, for the run's warnings: each unknown entity once with
  // its count, the malformed lines counted with the first few named.
  void skipped_warnings(std::vector<std::string>& out) const {
    for (const auto& [entity, seen] : unknown_)
      out.push_back(fmt::format("MGF: entity '{}' not read, {} line(s) skipped, the first at {}", entity, seen.count,
                                seen.first));
    if (skipped_ > 0) {
      std::string shown;
      for (const auto& s : skipped_lines_) shown += "; " + s;
      out.push_back(fmt::format("MGF: {} malformed line(s) skipped{}{}", skipped_, shown,
                                skipped_ > skipped_lines_.size() ? "; ..." : ""));
    }
    for (const auto& name : ones_)
      out.push_back(fmt::format("material '{}' reflects all the light it receives (rd 1): where such surfaces close "
                                "the scene the solve cannot converge and stops at solver.iterations", name));
  }

 private:
  // A malformed line: skipped with a warning.
  [[noreturn]] void fail(const std::string& msg) const { throw SkippedLine(file_error(path_, line_, msg)); }
  // A limit or an unreadable file: the scene is refused.
  [[noreturn]] void refuse(const std::string& msg) const { throw file_error(path_, line_, msg); }

  double number(const std::string& s, std::string_view what) const {
    double v = 0;
    auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec != std::errc() || p != s.data() + s.size()) fail(fmt::format("expected a number for {}, got '{}'", what, s));
    if (!std::isfinite(v)) fail(fmt::format("expected a finite number for {}, got '{}'", what, s));
    return v;
  }

  void expect(const std::vector<std::string>& t, size_t lo, size_t hi, std::string_view usage) const {
    if (t.size() - 1 < lo || t.size() - 1 > hi) fail(fmt::format("malformed '{}': expected '{}'", t[0], usage));
  }

  const Transform& transform() const { return xf_.empty() ? identity_ : xf_.back().total; }

  Vec3 vertex_point(const std::string& name) const { return transform().point(vertex(name).p); }

  const MgfVertex& vertex(const std::string& name) const {
    auto it = vertices_.find(name);
    if (it == vertices_.end()) fail(fmt::format("undefined vertex '{}'", name));
    return it->second;
  }

  // Returns the index of the last entry consumed.
  size_t execute(const std::vector<std::string>& t, const fs::path& path, size_t i, int depth) {
    const std::string& k = t[0];
    if (k == "c") define_context(t, colors_, unnamed_color_, current_color_, Chromaticity{});
    else if (k == "cxy") set_cxy(t);
    else if (k == "cspec") set_cspec(t);
    else if (k == "cct") {
      expect(t, 1, 1, "cct kelvin");
      const double kelvin = number(t[1], "cct");
      if (!(kelvin >= 500 && kelvin <= 1e6)) fail(fmt::format("'cct {}': a colour temperature must be 500 to 1e6 K", t[1]));
      *current_color_ = blackbody_chromaticity(kelvin);
    } else if (k == "cmix") set_cmix(t);
    else if (k == "m") {
      MgfMaterial fresh;
      fresh.sides = default_sides_;
      define_context(t, materials_, unnamed_material_, current_material_, fresh);
      material_name_ = t.size() > 1 ? t[1] : "";
    } else if (k == "rd") {
      expect(t, 1, 1, "rd reflectance");
      current_material_->rd = number(t[1], "rd");
      current_material_->rd_color = *current_color_;
    } else if (k == "ed") {
      expect(t, 1, 1, "ed emittance");
      current_material_->ed = number(t[1], "ed");
      if (current_material_->ed < 0) fail("emittance 'ed' must not be negative");
      current_material_->ed_color = *current_color_;
    } else if (k == "sides") {
      expect(t, 1, 1, "sides 1|2");
      if (t[1] != "1" && t[1] != "2") fail(fmt::format("'sides' must be 1 or 2, got '{}'", t[1]));
      current_material_->sides = t[1] == "1" ? 1 : 2;
    } else if (k == "rs" || k == "ts" || k == "td" || k == "ir") {
      // Specular and transmission properties: mpath solves diffuse reflection only.
    } else if (k == "v") define_vertex(t);
    else if (k == "p" || k == "n") set_vertex_vector(t);
    else if (k == "o") {
      if (t.size() > 2) fail("malformed 'o': expected 'o [name]'");
      if (t.size() == 2 && objects_.size() >= kMaxObjectDepth)
        refuse(fmt::format("objects nested more than {} deep ('o' without its closing 'o'?)", kMaxObjectDepth));
      if (t.size() == 2) objects_.push_back({t[1], -1});
      else if (objects_.empty()) fail("'o' end without a matching 'o name'");
      else objects_.pop_back();
    } else if (k == "xf") return transform_entity(t, i);
    else if (k == "i") include(t, path, depth);
    else if (k == "f") face(t);
    else if (k == "fh") unsupported("fh (faces with holes: split them into simple polygons)");
    else if (k == "sph") primitive_sphere(t);
    else if (k == "cyl" || k == "cone") primitive_cone(t);
    else if (k == "ring") primitive_ring(t);
    else if (k == "torus") primitive_torus(t);
    else if (k == "prism") primitive_prism(t);
    else if (k == "ies") unsupported("ies (IES luminaires: model the emitter with 'ed')");
    else unsupported(k.size() > 40 ? k.substr(0, 40) + "..." : k);
    return i;
  }

  // An entity mpath does not read (unknown, or not supported): counted, named once.
  void unsupported(const std::string& entity) {
    auto& seen = unknown_[entity];
    if (seen.count++ == 0) seen.first = fmt::format("{}:{}", path_, line_);
  }

  // c/m: "c" (unnamed default), "c id" (use, creating if new), "c id =" (reset), "c id = template".
  template <typename T>
  void define_context(const std::vector<std::string>& t, std::map<std::string, T>& named, T& unnamed, T*& current,
                      const T& fresh) {
    if (t.size() == 1) {
      unnamed = fresh;
      current = &unnamed;
      return;
    }
    if (t.size() > 4 || (t.size() >= 3 && t[2] != "=")) fail(fmt::format("malformed '{}': expected '{} [id [= [template]]]'", t[0], t[0]));
    auto [it, inserted] = named.try_emplace(t[1], fresh);
    if (t.size() == 3) it->second = fresh;
    if (t.size() == 4) {
      auto tmpl = named.find(t[3]);
      if (tmpl == named.end()) fail(fmt::format("undefined {} '{}'", t[0] == "c" ? "colour" : "material", t[3]));
      it->second = tmpl->second;
    }
    current = &it->second;
  }

  void set_cxy(const std::vector<std::string>& t) {
    expect(t, 2, 2, "cxy x y");
    const double x = number(t[1], "x"), y = number(t[2], "y");
    if (x < 0 || y <= 0 || x + y > 1) fail(fmt::format("chromaticity ({}, {}) is outside the CIE diagram", x, y));
    *current_color_ = {x, y};
  }

  void set_cspec(const std::vector<std::string>& t) {
    if (t.size() < 5) fail("malformed 'cspec': expected 'cspec lo_nm hi_nm v1 v2 ...'");
    const double lo = number(t[1], "lo_nm"), hi = number(t[2], "hi_nm");
    // The CIE observer sees 360 to 830 nm: a spectrum must overlap it, and carry some energy there.
    if (!(lo > 0 && hi > lo && hi - lo <= 1e4))
      fail(fmt::format("'cspec' range {} to {} nm: need 0 < lo < hi, at most 10000 nm apart", t[1], t[2]));
    if (hi <= 360 || lo >= 830) fail(fmt::format("'cspec' range {} to {} nm is outside the visible 360 to 830 nm", t[1], t[2]));
    std::vector<double> samples;
    double sum = 0;
    for (size_t i = 3; i < t.size(); ++i) {
      samples.push_back(number(t[i], "spectral value"));
      if (samples.back() < 0) fail(fmt::format("'cspec' value {} is negative", t[i]));
      sum += samples.back();
    }
    if (!(sum > 0)) fail("'cspec' has no energy (every value is 0): its colour is undefined");
    *current_color_ = spectrum_chromaticity(lo, hi, samples);
  }

  void set_cmix(const std::vector<std::string>& t) {
    if (t.size() < 3 || (t.size() - 1) % 2 != 0) fail("malformed 'cmix': expected 'cmix w1 c1 w2 c2 ...'");
    double X = 0, Y = 0, Z = 0;
    for (size_t i = 1; i + 1 < t.size(); i += 2) {
      const double w = number(t[i], "weight");
      auto it = colors_.find(t[i + 1]);
      if (it == colors_.end()) fail(fmt::format("undefined colour '{}'", t[i + 1]));
      const Chromaticity c = it->second;
      // Mix colours of unit luminance, weighted.
      X += w * c.x / c.y;
      Y += w;
      Z += w * (1 - c.x - c.y) / c.y;
    }
    if (X + Y + Z <= 0) fail("'cmix' weights must be positive");
    *current_color_ = {X / (X + Y + Z), Y / (X + Y + Z)};
  }

  void define_vertex(const std::vector<std::string>& t) {
    if (t.size() == 2) {
      auto it = vertices_.find(t[1]);
      if (it == vertices_.end()) fail(fmt::format("undefined vertex '{}'", t[1]));
      current_vertex_ = &it->second;
      return;
    }
    if ((t.size() != 3 && t.size() != 4) || t[2] != "=") fail("malformed 'v': expected 'v id = [template]'");
    MgfVertex v;
    if (t.size() == 4) v = vertex(t[3]);
    current_vertex_ = &(vertices_[t[1]] = v);
  }

  void set_vertex_vector(const std::vector<std::string>& t) {
    expect(t, 3, 3, t[0] + " x y z");
    if (!current_vertex_) fail(fmt::format("'{}' outside a vertex context (needs a 'v' before it)", t[0]));
    const Vec3 v{number(t[1], "x"), number(t[2], "y"), number(t[3], "z")};
    (t[0] == "p" ? current_vertex_->p : current_vertex_->n) = v;
  }

  // xf with arguments opens a context (repeated for -a arrays); xf alone closes it.
  size_t transform_entity(const std::vector<std::string>& t, size_t i) {
    if (t.size() > 1) {
      XfFrame frame;
      frame.args.assign(t.begin() + 1, t.end());
      frame.body_start = i + 1;
      frame.file = file_;
      frame.counts = array_counts(frame.args);
      frame.index.assign(frame.counts.size(), 0);
      refuse_array_bomb(frame.counts, "'xf -a'");
      frame.total = transform().after(parse_transform(frame.args, frame.index));
      xf_.push_back(std::move(frame));
      return i;
    }
    if (xf_.empty() || xf_.back().file != file_) fail("'xf' end without a matching 'xf' in this file");
    XfFrame& f = xf_.back();
    if (next_element(f.index, f.counts)) {
      const Transform outer = xf_.size() > 1 ? xf_[xf_.size() - 2].total : identity_;
      f.total = outer.after(parse_transform(f.args, f.index));
      return f.body_start - 1;
    }
    xf_.pop_back();
    return i;
  }

  // Nested arrays multiply, those of the open 'xf' contexts and includes with
  // `counts`: a bomb is refused before its body runs.
  void refuse_array_bomb(const std::vector<int>& counts, const char* what) const {
    double copies = 1;
    for (const XfFrame& open : xf_)
      for (int n : open.counts) copies *= n;
    for (int n : counts) copies *= n;
    if (copies > 1e7) refuse(fmt::format("nested {} arrays make {:.3g} copies (at most 1e7)", what, copies));
  }

  // Advances an array odometer to its next element, the last array fastest;
  // false (and all back at 0) after the last element.
  static bool next_element(std::vector<int>& index, const std::vector<int>& counts) {
    for (size_t d = counts.size(); d-- > 0;) {
      if (++index[d] < counts[d]) return true;
      index[d] = 0;
    }
    return false;
  }

  std::vector<int> array_counts(const std::vector<std::string>& args) const {
    std::vector<int> counts;
    for (size_t i = 0; i < args.size(); ++i)
      if (args[i] == "-a") {
        if (i + 1 >= args.size()) fail("'-a' needs a count");
        const double n = number(args[i + 1], "-a");
        if (n < 1 || n != std::floor(n) || n > 1e6) fail(fmt::format("'-a' count must be a positive integer, got {}", args[i + 1]));
        counts.push_back(static_cast<int>(n));
      }
    return counts;
  }

  // Composes the xf arguments left to right; after "-a N" (array element k) or
  // "-i N" the following arguments are applied k or N times.
  Transform parse_transform(const std::vector<std::string>& args, const std::vector<int>& index) const {
    Transform total;
    std::vector<Transform> segment_ops;
    int repeat = 1;
    size_t array = 0;
    auto flush = [&] {
      for (int r = 0; r < repeat; ++r)
        for (const Transform& op : segment_ops) total = op.after(total);
      segment_ops.clear();
    };
    for (size_t i = 0; i < args.size(); ++i) {
      const std::string& a = args[i];
      auto need = [&](size_t n) {
        if (i + n >= args.size()) fail(fmt::format("xf argument '{}' needs {} value(s)", a, n));
      };
      if (a == "-t") {
        need(3);
        segment_ops.push_back(Transform::translate({number(args[i + 1], "-t"), number(args[i + 2], "-t"), number(args[i + 3], "-t")}));
        i += 3;
      } else if (a == "-rx" || a == "-ry" || a == "-rz") {
        need(1);
        segment_ops.push_back(Transform::rotate(a[2] - 'x', number(args[++i], a)));
      } else if (a == "-s") {
        need(1);
        const double s = number(args[++i], "-s");
        if (s == 0) fail("xf scale '-s' must not be zero");
        segment_ops.push_back(Transform::scaling(s));
      } else if (a == "-mx" || a == "-my" || a == "-mz") {
        segment_ops.push_back(Transform::mirror(a[2] - 'x'));
      } else if (a == "-i" || a == "-a") {
        need(1);
        flush();
        if (a == "-a") {
          repeat = index[array++];
          ++i;
        } else {
          const double n = number(args[++i], "-i");
          if (!(n >= 0 && n <= 1e6) || n != std::floor(n))
            fail(fmt::format("'-i {}': the count must be a whole number from 0 to 1000000", args[i]));
          repeat = static_cast<int>(n);
        }
      } else {
        fail(fmt::format("unknown xf argument '{}'", a));
      }
    }
    flush();
    return total;
  }

  void include(const std::vector<std::string>& t, const fs::path& path, int depth) {
    if (t.size() < 2) fail("malformed 'i': expected 'i file [xf arguments]'");
    fs::path file = t[1];
    if (file.is_relative()) file = path.parent_path() / file;
    if (!fs::exists(file)) refuse(fmt::format("included file '{}' not found", file.string()));
    const std::vector<std::string> args(t.begin() + 2, t.end());
    // The file is read once per element of its arrays ('-a', as in 'xf').
    const std::vector<int> counts = array_counts(args);
    refuse_array_bomb(counts, "'-a'");
    const bool has_xf = !args.empty();
    std::vector<int> index(counts.size(), 0);
    do {
      // Includes that include each other twice over read 2^depth files: bounded.
      if (++includes_read_ > kMaxIncludeReads)
        refuse(fmt::format("more than {} files read through 'i' (includes that fan out or loop?)", kMaxIncludeReads));
      if (has_xf) {
        XfFrame frame;
        frame.total = transform().after(parse_transform(args, index));
        frame.counts = counts;  // arrays nested in the file multiply with this one's
        xf_.push_back(frame);
      }
      const std::string saved_path = path_;
      const long saved_line = line_;
      read_file(file, depth + 1);
      path_ = saved_path;
      line_ = saved_line;
      if (has_xf) xf_.pop_back();
    } while (next_element(index, counts));
  }

  int current_object() {
    if (objects_.empty()) {
      if (top_object_ < 0) {
        top_object_ = static_cast<int>(scene_.objects.size());
        scene_.objects.push_back({scene_.file.stem().string()});
      }
      return top_object_;
    }
    auto& [name, index] = objects_.back();
    if (index < 0) {
      std::string full;
      for (const auto& o : objects_) full += (full.empty() ? "" : "/") + o.first;
      index = static_cast<int>(scene_.objects.size());
      scene_.objects.push_back({full});
    }
    return index;
  }

  // The scene material for the current MGF material state.
  int current_scene_material() {
    const MgfMaterial& m = *current_material_;
    const Rgb rho = xyY_to_rgb(m.rd_color, m.rd);
    const Rgb exitance = xyY_to_rgb(m.ed_color, m.ed / kWhiteEfficacy);
    Material mat;
    mat.name = material_name_.empty() ? "default" : material_name_;
    for (int c = 0; c < 3; ++c) {
      mat.rho[c] = rho[c];
      mat.emission[c] = std::max(0.0, exitance[c]) / std::numbers::pi;
      if (rho[c] < 0 || rho[c] > 1.0 + 1e-9) {
        // Saturated colours can leave the RGB gamut: keep them physical and say so.
        mat.rho[c] = std::clamp(rho[c], 0.0, 0.99);
        gamut_warnings_.insert(mat.name);
      } else {
        mat.rho[c] = std::fabs(rho[c] - 1.0) <= 1e-9 ? 1.0 : rho[c];  // rd 1 in white is 1, not 1 -+ rounding
      }
    }
    mat.two_sided = m.sides == 2;
    mat.invisible_back = !mat.two_sided;  // the specification: a one-sided surface is invisible from behind
    if (m.rd < 0 || m.rd > 1) fail(fmt::format("material '{}': reflectance rd {} is outside [0, 1]", mat.name, m.rd));
    if (m.rd == 1) ones_.insert(mat.name);
    const auto key = std::make_tuple(mat.name, mat.rho, mat.emission, mat.two_sided);
    auto it = material_index_.find(key);
    if (it != material_index_.end()) return it->second;
    // A material name redefined with other values gets a distinct scene material.
    const int same_name = static_cast<int>(std::count_if(scene_.materials.begin(), scene_.materials.end(),
                                                         [&](const Material& x) { return x.name.rfind(mat.name, 0) == 0; }));
    if (scene_.find_material(mat.name) >= 0) mat.name += fmt::format("#{}", same_name);
    scene_.materials.push_back(mat);
    return material_index_[key] = static_cast<int>(scene_.materials.size()) - 1;
  }

  void add_polygon(std::vector<Vec3> vertices) {
    if (transform().determinant() < 0) std::reverse(vertices.begin(), vertices.end());
    add_world_polygon(std::move(vertices));
  }

  void add_world_polygon(std::vector<Vec3> vertices) {
    if (scene_.polygons.size() >= kMaxPolygons)
      refuse(fmt::format("more than {} polygons (runaway 'xf -a' arrays or includes?)", kMaxPolygons));
    Polygon poly;
    poly.vertices = std::move(vertices);
    poly.material = current_scene_material();
    poly.object = current_object();
    scene_.polygons.push_back(std::move(poly));
  }

  void add_world_polygons(const PolygonList& polygons) {
    for (const auto& p : polygons) add_world_polygon(p);
  }

  void face(const std::vector<std::string>& t) {
    if (t.size() < 4) fail("malformed 'f': expected at least 3 vertices");
    std::vector<Vec3> v;
    for (size_t i = 1; i < t.size(); ++i) v.push_back(vertex_point(t[i]));
    add_polygon(std::move(v));
  }

  double radius(const std::string& s, std::string_view what) const { return number(s, what) * transform().scale(); }

  void primitive_sphere(const std::vector<std::string>& t) {
    expect(t, 2, 2, "sph v radius");
    const double r = radius(t[2], "radius");
    if (r == 0) fail("sphere radius must not be zero");
    add_world_polygons(tessellate_sphere(vertex_point(t[1]), std::fabs(r), segments_, r < 0));
  }

  void primitive_cone(const std::vector<std::string>& t) {
    const bool cyl = t[0] == "cyl";
    expect(t, cyl ? 3 : 4, cyl ? 3 : 4, cyl ? "cyl v1 radius v2" : "cone v1 radius1 v2 radius2");
    const double r1 = radius(t[2], "radius");
    const double r2 = cyl ? r1 : radius(t[4], "radius2");
    if (r1 * r2 < 0 || (r1 == 0 && r2 == 0)) fail(fmt::format("'{}' radii must have one sign and not both be zero", t[0]));
    const Vec3 a = vertex_point(t[1]), b = vertex_point(t[3]);
    if (length(b - a) == 0) fail(fmt::format("'{}' end points coincide", t[0]));
    add_world_polygons(tessellate_cone(a, std::fabs(r1), b, std::fabs(r2), segments_, r1 < 0 || r2 < 0));
  }

  Vec3 vertex_normal(const std::string& name) const {
    const Vec3 n = transform().vector(vertex(name).n);
    if (length(n) == 0) fail(fmt::format("vertex '{}' needs a normal 'n' for this primitive", name));
    return n;
  }

  void primitive_ring(const std::vector<std::string>& t) {
    expect(t, 3, 3, "ring v inner_radius outer_radius");
    const double r0 = radius(t[2], "inner radius"), r1 = radius(t[3], "outer radius");
    if (r0 < 0 || r1 <= r0) fail("'ring' needs 0 <= inner radius < outer radius");
    add_world_polygons(tessellate_ring(vertex_point(t[1]), vertex_normal(t[1]), r0, r1, segments_));
  }

  void primitive_torus(const std::vector<std::string>& t) {
    expect(t, 3, 3, "torus v inner_radius outer_radius");
    const double r0 = radius(t[2], "inner radius"), r1 = radius(t[3], "outer radius");
    if (r0 * r1 < 0 || std::fabs(r1) <= std::fabs(r0)) fail("'torus' needs radii of one sign with |inner| < |outer|");
    add_world_polygons(tessellate_torus(vertex_point(t[1]), vertex_normal(t[1]), std::fabs(r0), std::fabs(r1), segments_, r0 < 0));
  }

  void primitive_prism(const std::vector<std::string>& t) {
    if (t.size() < 5) fail("malformed 'prism': expected 'prism v1 v2 v3 ... length'");
    std::vector<Vec3> base;
    for (size_t i = 1; i + 1 < t.size(); ++i) base.push_back(vertex_point(t[i]));
    if (transform().determinant() < 0) std::reverse(base.begin(), base.end());
    if (polygon_area(base) == 0) fail("'prism' base polygon has no area");
    add_world_polygons(tessellate_prism(base, radius(t.back(), "length")));
  }

 public:
  std::set<std::string> gamut_warnings_;

 private:
  static constexpr size_t kSkippedShown = 3;
  struct Unknown {
    size_t count = 0;
    std::string first;
  };
  std::map<std::string, Unknown> unknown_;
  size_t skipped_ = 0;
  std::vector<std::string> skipped_lines_;
  std::set<std::string> ones_;

 private:
  Scene& scene_;
  int segments_;
  int default_sides_;
  std::string path_;
  long line_ = 0;
  int file_ = 0;
  int files_read_ = 0;
  std::map<std::string, Chromaticity> colors_;
  Chromaticity unnamed_color_;
  Chromaticity* current_color_;
  size_t includes_read_ = 0;  // files read through `i`, over the whole scene
  std::map<std::string, MgfMaterial> materials_;
  MgfMaterial unnamed_material_;
  MgfMaterial* current_material_;
  std::string material_name_;
  std::map<std::string, MgfVertex> vertices_;
  MgfVertex* current_vertex_ = nullptr;
  std::vector<XfFrame> xf_;
  Transform identity_;
  std::vector<std::pair<std::string, int>> objects_;
  int top_object_ = -1;
  std::map<std::tuple<std::string, Rgb, Rgb, bool>, int> material_index_;
};

}  // namespace

Scene read_mgf(const fs::path& path, int curve_segments, int default_sides, std::vector<std::string>* warnings) {
  Scene scene;
  scene.file = path;
  MgfReader reader(scene, curve_segments, default_sides);
  reader.read_file(path, 0);
  std::vector<std::string> skipped;
  reader.skipped_warnings(skipped);
  // Nothing usable left: the error says what was skipped.
  if (scene.polygons.empty() && !skipped.empty())
    throw InputError(fmt::format("{}: no polygon could be read ({})", path.string(), skipped.front()));
  if (warnings) warnings->insert(warnings->end(), skipped.begin(), skipped.end());
  if (warnings)
    for (const auto& name : reader.gamut_warnings_)
      warnings->push_back(fmt::format("material '{}': colour outside the RGB gamut, reflectance clamped to [0, 0.99]", name));
  return scene;
}

}  // namespace mpath
