#include <limits>
#include "config_keys.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>
#include <sstream>

#include "error.h"

namespace mpath {
namespace {

namespace fs = std::filesystem;

[[noreturn]] void bad_value(const ValueSource& src, const std::string& what) {
  throw InputError(fmt::format("{}: config key '{}': {}", src.where, src.key, what));
}

const char* type_name(const toml::node& node) {
  switch (node.type()) {
    case toml::node_type::string: return "a string";
    case toml::node_type::integer: return "an integer";
    case toml::node_type::floating_point: return "a number";
    case toml::node_type::boolean: return "a boolean";
    case toml::node_type::array: return "an array";
    case toml::node_type::table: return "a table";
    default: return "a date or time";
  }
}

double get_number(const toml::node& node, const ValueSource& src) {
  if (auto v = node.value_exact<double>()) {
    if (!std::isfinite(*v)) bad_value(src, "expected a finite number");
    return *v;
  }
  if (auto v = node.value_exact<int64_t>()) return static_cast<double>(*v);
  bad_value(src, fmt::format("expected a number, got {}", type_name(node)));
}

long long get_integer(const toml::node& node, const ValueSource& src) {
  if (auto v = node.value_exact<int64_t>()) return *v;
  bad_value(src, fmt::format("expected an integer, got {}", type_name(node)));
}

bool get_bool(const toml::node& node, const ValueSource& src) {
  if (auto v = node.value_exact<bool>()) return *v;
  bad_value(src, fmt::format("expected true or false, got {}", type_name(node)));
}

std::string get_string(const toml::node& node, const ValueSource& src) {
  if (auto v = node.value_exact<std::string>()) return *v;
  bad_value(src, fmt::format("expected a string, got {}", type_name(node)));
}

// A string that must be one of `choices`; `what` names it in the error.
std::string get_choice(const toml::node& node, const ValueSource& src, const char* what,
                       std::initializer_list<const char*> choices) {
  std::string v = get_string(node, src);
  std::string known;
  for (const char* c : choices) {
    if (v == c) return v;
    known += (known.empty() ? "" : ", ") + std::string(c);
  }
  bad_value(src, fmt::format("unknown {} '{}' (known: {})", what, v, known));
}

fs::path get_path(const toml::node& node, const ValueSource& src) {
  fs::path p = get_string(node, src);
  if (p.empty()) bad_value(src, "expected a non-empty path");
  return p.is_absolute() ? p : (src.base_dir / p).lexically_normal();
}

Vec3 get_vec3(const toml::node& node, const ValueSource& src) {
  const toml::array* arr = node.as_array();
  if (!arr || arr->size() != 3)
    bad_value(src, fmt::format("expected an array of 3 numbers, got {}", type_name(node)));
  Vec3 v;
  for (int i = 0; i < 3; ++i) v[i] = get_number(*arr->get(i), src);
  return v;
}

long long positive(long long v, const ValueSource& src) {
  if (v <= 0) bad_value(src, fmt::format("expected a positive integer, got {}", v));
  return v;
}

// The most lines a store or a first shot may have: 1e12 lines take about
// 7 TB of store and days of tracing on a cluster; more is a typing error.
constexpr long long kMaxLines = 1'000'000'000'000LL;

// A positive integer of at most `most`: a larger one is an error, not clamped.
long long positive_at_most(long long v, long long most, const ValueSource& src) {
  positive(v, src);
  if (v > most) bad_value(src, fmt::format("at most {} (got {})", most, v));
  return v;
}

// 0 (the key's automatic choice) up to `most`.
long long zero_or_at_most(long long v, long long most, const ValueSource& src) {
  if (v == 0) return 0;
  return positive_at_most(v, most, src);
}

double in_range(double v, double lo, double hi, const ValueSource& src) {
  if (!(v >= lo && v <= hi)) bad_value(src, fmt::format("expected a value in [{}, {}], got {}", lo, hi, v));
  return v;
}

// [r, g, b] or one number for all three, each from 0 to `most`.
Rgb get_rgb(const toml::node& node, const ValueSource& src, std::string_view what, double most) {
  Rgb rgb;
  if (node.is_number()) {
    const double g = get_number(node, src);
    rgb = {g, g, g};
  } else {
    const Vec3 v = get_vec3(node, src);
    rgb = {v.x, v.y, v.z};
  }
  for (double c : rgb) {
    if (c < 0) bad_value(src, fmt::format("{} must not be negative", what));
    if (c > most) bad_value(src, fmt::format("{} must be at most {}", what, most));
  }
  return rgb;
}

// A one-element array holding `value` (toml::array{an_array} would copy the
// array instead of nesting it).
template <typename T>
toml::array one(T&& value) {
  toml::array out;
  out.push_back(std::forward<T>(value));
  return out;
}

// The source of `node`, an entry `name` of the table read from `parent`: its
// own line in the config file, or the command line when an override put it
// there (a table may hold entries of both).
ValueSource entry_source(const ValueSource& parent, const std::string& key, const toml::node& node) {
  ValueSource src = parent;
  src.key = key;
  if (const auto& path = node.source().path; path) {
    src.where = fmt::format("{}:{}", *path, node.source().begin.line);
    src.from_command_line = false;
    src.base_dir = std::filesystem::path(*path).parent_path();
  } else {
    src.where = "command line";
    src.from_command_line = true;
    src.base_dir = std::filesystem::current_path();
  }
  return src;
}

// A table `material = [r, g, b]` of the config into a map of Options.
ConfigKey rgb_table_key(const char* key, const char* help, std::map<std::string, Rgb> SceneOptions::*member,
                        const char* what, double most) {
  return {key, help,
          [=](const toml::node& n, const ValueSource& s, Options& o) {
            const toml::table* t = n.as_table();
            if (!t) bad_value(s, fmt::format("expected a table of material = [r, g, b], got {}", type_name(n)));
            auto& out = o.scene.*member;
            out.clear();
            for (const auto& [name, value] : *t)
              out[std::string(name.str())] =
                  get_rgb(value, entry_source(s, s.key + "." + std::string(name.str()), value), what, most);
          },
          [=](const Options& o) {
            toml::table table;
            for (const auto& [name, rgb] : o.scene.*member) table.insert(name, toml::array{rgb[0], rgb[1], rgb[2]});
            return one(std::move(table));
          }};
}

// A camera's or grid's name names its files in output.dir (NAME.exr,
// NAME.csv, ...): a plain file name, never a path.
std::string get_file_name(const toml::node& node, const ValueSource& src) {
  const std::string name = get_string(node, src);
  const bool plain = !name.empty() && name.size() <= 100 && name[0] != '.' &&
                     std::all_of(name.begin(), name.end(), [](unsigned char c) {
                       return std::isalnum(c) || c == '_' || c == '-' || c == '.';
                     });
  if (!plain)
    bad_value(src, fmt::format("'{}' is not a plain file name (letters, digits, '_', '-', '.', not starting with "
                               "'.', at most 100 characters): it names files in output.dir", name));
  return name;
}

// Each entry of table `index` of an array of tables ([[camera]] and the
// like), with where it came from (`camera[2].position`).
template <typename F>
void for_each_entry(const toml::table& table, const ValueSource& parent, size_t index, const F& f) {
  for (const auto& [k, node] : table)
    f(std::string(k.str()), node, entry_source(parent, fmt::format("{}[{}].{}", parent.key, index, std::string(k.str())), node));
}

CameraOptions get_camera(const toml::table& table, const ValueSource& parent, size_t index) {
  CameraOptions cam;
  cam.name = fmt::format("camera{}", index);
  for_each_entry(table, parent, index, [&](const std::string& key, const toml::node& node, const ValueSource& src) {
    if (key == "name") cam.name = get_file_name(node, src);
    else if (key == "position") cam.position = get_vec3(node, src);
    else if (key == "look_at") cam.look_at = get_vec3(node, src);
    else if (key == "up") cam.up = get_vec3(node, src);
    else if (key == "fov_deg") cam.fov_deg = in_range(get_number(node, src), 1.0, 179.0, src);
    else if (key == "width") cam.width = static_cast<int>(positive_at_most(get_integer(node, src), 16384, src));
    else if (key == "height") cam.height = static_cast<int>(positive_at_most(get_integer(node, src), 16384, src));
    else if (key == "samples") cam.samples = static_cast<int>(positive_at_most(get_integer(node, src), 4096, src));
    else if (key == "exposure") cam.exposure = get_number(node, src);
    else bad_value(src, "unknown key");
  });
  if (length(cam.look_at - cam.position) == 0.0) bad_value(parent, "camera position equals look_at");
  if (length(cross(cam.look_at - cam.position, cam.up)) == 0.0) bad_value(parent, "camera up is parallel to the view direction");
  return cam;
}

GridOptions get_grid(const toml::table& table, const ValueSource& parent, size_t index) {
  GridOptions grid;
  grid.name = fmt::format("grid{}", index);
  bool has_origin = false, has_u = false, has_v = false;
  for_each_entry(table, parent, index, [&](const std::string& key, const toml::node& node, const ValueSource& src) {
    if (key == "name") grid.name = get_file_name(node, src);
    else if (key == "origin") has_origin = (grid.origin = get_vec3(node, src), true);
    else if (key == "u") has_u = (grid.u = get_vec3(node, src), true);
    else if (key == "v") has_v = (grid.v = get_vec3(node, src), true);
    else if (key == "nu") grid.nu = static_cast<int>(positive_at_most(get_integer(node, src), 1000, src));
    else if (key == "nv") grid.nv = static_cast<int>(positive_at_most(get_integer(node, src), 1000, src));
    else if (key == "normal") grid.normal = get_vec3(node, src);
    else if (key == "samples") grid.samples = static_cast<int>(positive_at_most(get_integer(node, src), 1 << 20, src));
    else bad_value(src, "unknown key");
  });
  if (!has_origin || !has_u || !has_v) bad_value(parent, fmt::format("grid {} needs `origin`, `u` and `v`", index));
  if (length(cross(grid.u, grid.v)) == 0.0 && length(grid.normal) == 0.0)
    bad_value(parent, fmt::format("grid '{}': u and v are parallel (or zero) and no `normal` is given", grid.name));
  if (static_cast<long long>(grid.nu) * grid.nv * grid.samples > 4'000'000'000LL)
    bad_value(parent, fmt::format("grid '{}': {} x {} points of {} rays is more than 4e9 rays", grid.name, grid.nu,
                                  grid.nv, grid.samples));
  return grid;
}

LightOptions get_light(const toml::table& table, const ValueSource& parent, size_t index) {
  LightOptions light;
  light.name = fmt::format("light{}", index);
  bool placed = false;
  for_each_entry(table, parent, index, [&](const std::string& key, const toml::node& node, const ValueSource& src) {
    if (key == "name") light.name = get_file_name(node, src);
    else if (key == "position") placed = (light.position = get_vec3(node, src), true);
    else if (key == "intensity_cd") light.intensity_cd = in_range(get_number(node, src), 0.0, 1e10, src);
    else if (key == "ies") light.ies = get_path(node, src);
    else if (key == "multiplier") light.multiplier = in_range(get_number(node, src), 0.0, 1e6, src);
    else if (key == "nadir") light.nadir = get_vec3(node, src);
    else if (key == "c0") light.c0 = get_vec3(node, src);
    else bad_value(src, "unknown key");
  });
  if (!placed) bad_value(parent, fmt::format("light {} needs a `position`", index));
  if ((light.intensity_cd > 0) == !light.ies.empty())
    bad_value(parent, fmt::format("light '{}' needs one of `intensity_cd` (isotropic) and `ies` (a photometric file)",
                                  light.name));
  if (length(light.nadir) == 0 || length(cross(light.nadir, light.c0)) == 0)
    bad_value(parent, fmt::format("light '{}': `nadir` must be non-zero and not parallel to `c0`", light.name));
  return light;
}

SolverMethod get_method(const toml::node& node, const ValueSource& src) {
  const std::string name = get_choice(node, src, "method", {"hierarchical", "multipath", "classic"});
  return name == "hierarchical" ? SolverMethod::hierarchical
         : name == "multipath"  ? SolverMethod::multipath
                                : SolverMethod::classic;
}


toml::array vec_to_toml(const Vec3& v) { return toml::array{v.x, v.y, v.z}; }

toml::table grid_table(const GridOptions& g) {
  return toml::table{{"name", g.name}, {"origin", vec_to_toml(g.origin)}, {"u", vec_to_toml(g.u)},
                     {"v", vec_to_toml(g.v)}, {"nu", g.nu}, {"nv", g.nv}, {"normal", vec_to_toml(g.normal)},
                     {"samples", g.samples}};
}

toml::table light_table(const LightOptions& l) {
  toml::table t{{"name", l.name}, {"position", vec_to_toml(l.position)}, {"multiplier", l.multiplier},
                {"nadir", vec_to_toml(l.nadir)}, {"c0", vec_to_toml(l.c0)}};
  if (l.ies.empty()) t.insert("intensity_cd", l.intensity_cd);
  else t.insert("ies", l.ies.string());
  return t;
}

toml::table camera_table(const CameraOptions& c) {
  return toml::table{{"name", c.name}, {"position", vec_to_toml(c.position)}, {"look_at", vec_to_toml(c.look_at)},
                     {"up", vec_to_toml(c.up)}, {"fov_deg", c.fov_deg}, {"width", c.width}, {"height", c.height},
                     {"samples", c.samples}, {"exposure", c.exposure}};
}

// An array of tables ([[camera]], [[light]], [[grid]]) read into the vector
// `of(options)` by `read`; two of one name are an error (a name names files
// and report entries).
template <typename T>
ConfigKey table_array_key(const char* key, const char* help, std::vector<T>& (*of)(Options&),
                          T (*read)(const toml::table&, const ValueSource&, size_t), toml::table (*write)(const T&),
                          const char* plural) {
  return {key, help,
          [=](const toml::node& n, const ValueSource& s, Options& o) {
            std::vector<T>& out = of(o);
            out.clear();
            if (const toml::table* t = n.as_table()) {
              out.push_back(read(*t, s, 0));
              return;
            }
            const toml::array* a = n.as_array();
            if (!a || !a->is_array_of_tables()) bad_value(s, fmt::format("expected [[{}]] tables", key));
            for (size_t i = 0; i < a->size(); ++i) {
              out.push_back(read(*a->get(i)->as_table(), s, i));
              for (size_t j = 0; j < i; ++j)
                if (out[j].name == out[i].name)
                  bad_value(s, fmt::format("{} {} and {} are both named '{}' (their files would overwrite each other)",
                                           plural, j, i, out[i].name));
            }
          },
          [=](const Options& o) {
            const std::vector<T>& in = of(const_cast<Options&>(o));
            if (in.empty()) return toml::array{};
            toml::array all;
            for (const T& x : in) all.push_back(write(x));
            return one(std::move(all));
          }};
}

// A row's reader and printer: `o` is the options, `n` the TOML value and `s` where it came from.
#define SET(...) [](const toml::node& n, const ValueSource& s, Options& o) { __VA_ARGS__; }
#define GET(...) [](const Options& o) { return toml::array{__VA_ARGS__}; }

std::vector<ConfigKey> make_table() {
  return {
      {"scene.file", "OBJ, PLY or MGF file, relative to the config file (required)",
       SET(o.scene.file = get_path(n, s)),
       [](const Options& o) { return o.scene.file.empty() ? toml::array{} : toml::array{o.scene.file.string()}; }},
      rgb_table_key("scene.emitters",
                    "table `material = [r, g, b]` (or one number): emitted radiance in W/sr/m2, overriding the file",
                    &SceneOptions::emitters, "emitted radiance", std::numeric_limits<double>::infinity()),
      rgb_table_key("scene.materials",
                    "table `material = [r, g, b]` (or one number): diffuse reflectance, overriding the file (a kept "
                    "store still serves)",
                    &SceneOptions::materials, "a reflectance", 1.0),
      {"scene.two_sided", "material names whose surfaces have two faces, each with its own radiosity",
       SET(const toml::array* a = n.as_array();
           if (!a) bad_value(s, fmt::format("expected an array of material names, got {}", type_name(n)));
           o.scene.two_sided.clear();
           for (const auto& v : *a) o.scene.two_sided.push_back(get_string(v, s))),
       [](const Options& o) {
         toml::array names;
         for (const auto& name : o.scene.two_sided) names.push_back(name);
         return one(std::move(names));
       }},
      {"scene.mgf_default_sides", "sides of MGF materials without a `sides` entity (see scene-formats.md)",
       SET(const long long v = get_integer(n, s);
           if (v != 1 && v != 2) bad_value(s, fmt::format("expected 1 or 2, got {}", v));
           o.scene.mgf_default_sides = static_cast<int>(v)),
       GET(o.scene.mgf_default_sides)},
      {"mesh.max_patch_area", "largest patch area in scene units squared; 0: automatic, the scene box area / 2000",
       SET(o.mesh.max_patch_area = get_number(n, s);
           if (o.mesh.max_patch_area < 0) bad_value(s, "expected a positive area (or 0 for automatic)")),
       GET(o.mesh.max_patch_area)},
      {"mesh.curve_segments", "segments around a circle when tessellating MGF curved primitives",
       SET(o.mesh.curve_segments = static_cast<int>(get_integer(n, s));
           if (o.mesh.curve_segments < 3 || o.mesh.curve_segments > 1024) bad_value(s, "expected an integer in [3, 1024]")),
       GET(o.mesh.curve_segments)},
      {"mesh.split_contacts",
       "also split polygons pressed against another (a frame on a wall) into their part in contact and the rest, so "
       "that the covered part has a radiosity of its own; without it, touching surfaces already exchange nothing and "
       "a straddling patch holds the area mean (see scene-formats.md, \"Surfaces in contact\")",
       SET(o.mesh.split_contacts = get_bool(n, s)), GET(o.mesh.split_contacts)},
      {"mesh.contact_min_area",
       "contacts of at most this area (scene units squared) are left whole unless they cover a fifth of the smaller "
       "object; 0: the largest patch area",
       SET(o.mesh.contact_min_area = get_number(n, s);
           if (!(o.mesh.contact_min_area >= 0) || !std::isfinite(o.mesh.contact_min_area))
             bad_value(s, "expected an area >= 0 (0: the largest patch area)")),
       GET(o.mesh.contact_min_area)},
      {"hierarchy.group_threshold", "two items group when (sum of their box areas) / (area of the merged box) exceeds this",
       SET(o.hierarchy.group_threshold = in_range(get_number(n, s), 0.0, 1e9, s)), GET(o.hierarchy.group_threshold)},
      {"hierarchy.vp_area_ratio",
       "a virtual patch's area is at most this times `mesh.max_patch_area` (grid 2^k x 2^k, at most 64 x 64)",
       SET(o.hierarchy.vp_area_ratio = in_range(get_number(n, s), 1e-6, 1e9, s)), GET(o.hierarchy.vp_area_ratio)},
      {"hierarchy.vp_grid", "fixed VP grid per box face (a power of two up to 64); 0: from `vp_area_ratio`",
       SET(const long long g = get_integer(n, s);
           if (g < 0 || g > 64 || (g & (g - 1)) != 0) bad_value(s, "expected 0 (automatic) or a power of two up to 64");
           o.hierarchy.vp_grid = static_cast<int>(g)),
       GET(o.hierarchy.vp_grid)},
      {"hierarchy.max_share", "largest subscene box, as a share of the scene box's surface area",
       SET(o.hierarchy.max_share = in_range(get_number(n, s), 0.0, 1.0, s)), GET(o.hierarchy.max_share)},
      {"hierarchy.max_depth", "deepest subscene level; 0: no subscenes (algorithm.md: one level measured best)",
       SET(o.hierarchy.max_depth = static_cast<int>(in_range(get_integer(n, s), 0, 64, s))), GET(o.hierarchy.max_depth)},
      {"hierarchy.transport",
       "`\"transmittance\"` (the paper's: virtual walls with angular regions and transmittances) or `\"lines\"` (a "
       "box's lines see everything inside it; each pair of patches is carried by the smallest box holding both; no "
       "power held in walls); see algorithm.md",
       SET(o.hierarchy.transport = get_choice(n, s, "transport", {"transmittance", "lines"})),
       GET(o.hierarchy.transport)},
      {"lines.total",
       "stored lines in all boxes (hierarchical, multipath), or global lines of the first pass (classic; later passes use fewer)",
       SET(o.lines.total = positive_at_most(get_integer(n, s), kMaxLines, s)), GET(static_cast<int64_t>(o.lines.total))},
      {"lines.root_fraction", "share of lines in the root box (hierarchical method, `lines.box_budget` `\"quotient\"` or `\"objects\"`)",
       SET(o.lines.root_fraction = in_range(get_number(n, s), 0.0, 1.0, s)), GET(o.lines.root_fraction)},
      {"lines.box_budget",
       "how the boxes share the lines: `\"pilot\"` (a cheap pilot of `lines.pilot` local and global lines estimates "
       "where the error lies and sets the root's share, at least 2/3, and the subscenes', and a lamp's small group "
       "below `hierarchy.max_depth` is a subscene of its own; less error at equal lines, but the store's lines and "
       "boxes then depend on the materials; see algorithm.md), or the paper's rule: `lines.root_fraction` in the "
       "root and the rest by grouping `\"quotient\"` or by `\"objects\"`",
       SET(o.lines.box_budget = get_choice(n, s, "budget", {"quotient", "objects", "pilot"})), GET(o.lines.box_budget)},
      {"lines.pilot",
       "local lines from the emitters and global lines of the pilot of `lines.box_budget = \"pilot\"` (at most a "
       "quarter of `lines.total`); 0: a twentieth of `lines.total`, at least 50,000 and at most 200,000",
       SET(o.lines.pilot = zero_or_at_most(get_integer(n, s), kMaxLines, s)), GET(static_cast<int64_t>(o.lines.pilot))},
      {"lines.min_density",
       "no subscene gets fewer lines per unit of box surface than this times the root's (all boxes scaled down alike "
       "when the floors ask for more than `lines.total`)",
       SET(o.lines.min_density = in_range(get_number(n, s), 0.0, 1e6, s)), GET(o.lines.min_density)},
      {"lines.seed", "seed of every random choice; same config and seed give identical results on any number of threads",
       SET(const long long v = get_integer(n, s);
           if (v < 0) bad_value(s, "expected a non-negative integer");
           o.lines.seed = static_cast<unsigned long long>(v)),
       GET(static_cast<int64_t>(o.lines.seed))},
      {"lines.sequence", "`\"halton\"` (randomised Halton) or `\"random\"` global lines; see algorithm.md",
       SET(o.lines.sequence = get_choice(n, s, "sequence", {"random", "halton"})), GET(o.lines.sequence)},
      {"first_shot.lines", "local lines of the first shot, shared among the emitting faces and the `[[light]]`s by "
                           "power; 0: a pilot sets them (1/8 to 4 times lines.total, by where the error lies)",
       SET(o.first_shot.lines = zero_or_at_most(get_integer(n, s), kMaxLines, s)), GET(static_cast<int64_t>(o.first_shot.lines))},
      {"first_shot.accelerate",
       "hierarchical method: local lines entering a subscene are tested against the AR's associated patches first "
       "(algorithm.md)",
       SET(o.first_shot.accelerate = get_bool(n, s)), GET(o.first_shot.accelerate)},
      {"first_shot.mode",
       "`\"auto\"`: an emitting face that global lines sample better is shot by them; `\"local\"`: every emitter by "
       "local lines",
       SET(o.first_shot.mode = get_choice(n, s, "mode", {"auto", "local"})), GET(o.first_shot.mode)},
      {"first_shot.sequence",
       "`\"halton\"` (each emitting face's and each `[[light]]`'s lines stratified by a randomised Halton sequence "
       "of its own) or "
       "`\"random\"`; see algorithm.md",
       SET(o.first_shot.sequence = get_choice(n, s, "sequence", {"random", "halton"})), GET(o.first_shot.sequence)},
      {"second_shot.share",
       "local lines of the second shot, as a share of `lines.total`: after the first shot, the faces holding the "
       "most unshot power for their size (a lamp's shade lit by its bulb) shoot it with local lines instead of "
       "leaving it to the global lines, each where it would get more local lines than global crossings; 0: none "
       "(algorithm.md)",
       SET(o.second_shot.share = in_range(get_number(n, s), 0.0, 4.0, s)), GET(o.second_shot.share)},
      {"solver.method",
       "`\"hierarchical\"`, `\"multipath\"` (stored lines, root box only) or `\"classic\"` (fresh lines, no store)",
       SET(o.solver.method = get_method(n, s)), GET(std::string(to_string(o.solver.method)))},
      {"solver.iterations", "cap on passes (classic) or iterations over the stored lines",
       SET(o.solver.iterations = static_cast<int>(positive_at_most(get_integer(n, s), 100000, s))),
       GET(o.solver.iterations)},
      {"solver.tolerance", "stop when (unshot power + power held in ARs) / emitted power falls below this",
       SET(o.solver.tolerance = in_range(get_number(n, s), 0.0, 1.0, s)), GET(o.solver.tolerance)},
      {"solver.threads", "worker threads; 0 uses every hardware thread; more than the cores are started as asked",
       SET(o.solver.threads = static_cast<int>(in_range(get_integer(n, s), 0, 4096, s))), GET(o.solver.threads)},
      {"solver.shards",
       "each pass's work in this many parts, merged in their order, so that threads and MPI ranks do not change the "
       "answer; at most this many threads or ranks share a pass; each part holds 64 bytes per face (the "
       "hierarchical method: 50-100 bytes per face of its box, and on one rank only about as many parts as threads "
       "at once)",
       SET(o.solver.shards = static_cast<int>(positive_at_most(get_integer(n, s), 4096, s))), GET(o.solver.shards)},
      {"solver.checkpoint_seconds",
       "checkpoint.bin is written after the first shot or a pass that ends at least this many seconds after the solve "
       "began or it was last written, and after the last pass; 0: after the first shot and every pass",
       SET(o.solver.checkpoint_seconds = in_range(get_number(n, s), 0.0, 1e9, s)), GET(o.solver.checkpoint_seconds)},
      {"solver.adaptive_lines",
       "stored-line methods: later iterations take a share of each box's lines in proportion to the power it has left "
       "to send (with the hierarchy's line sets a larger share, or every line, where that sends more power per line "
       "or reaches solver.tolerance for less work)",
       SET(o.solver.adaptive_lines = get_bool(n, s)), GET(o.solver.adaptive_lines)},
      {"solver.schedule",
       "hierarchical: `\"v-cycle\"` (subscenes deepest first, the root, then top-down) or `\"top-down\"` (the paper's "
       "MP(root))",
       SET(o.solver.schedule = get_choice(n, s, "schedule", {"v-cycle", "top-down"})), GET(o.solver.schedule)},
      {"store.dir", "line store folder (relative to the config file)", SET(o.store.dir = get_path(n, s)),
       GET(o.store.dir.string())},
      {"store.chunk_lines", "lines per compressed chunk (shapes the store)",
       SET(o.store.chunk_lines = static_cast<int>(in_range(get_integer(n, s), 256, 1 << 24, s))), GET(o.store.chunk_lines)},
      {"store.zstd_level", "zstd level of the chunks (higher: smaller stores, slower preprocessing)",
       SET(o.store.zstd_level = static_cast<int>(in_range(get_integer(n, s), 1, 19, s))), GET(o.store.zstd_level)},
      {"output.dir", "result folder (relative to the config file), created if missing", SET(o.output.dir = get_path(n, s)),
       GET(o.output.dir.string())},
      {"output.exr", "an EXR image per camera", SET(o.output.exr = get_bool(n, s)), GET(o.output.exr)},
      {"output.png", "a tone-mapped PNG preview beside each EXR", SET(o.output.png = get_bool(n, s)), GET(o.output.png)},
      {"output.grids", "measure and write the `[[grid]]` illuminance grids (false: skip them on this run)",
       SET(o.output.grids = get_bool(n, s)), GET(o.output.grids)},
      table_array_key<CameraOptions>(
          "camera",
          "`name`, `position`, `look_at`, `up` (`[0,1,0]`), `fov_deg` (vertical, 40), `width`, `height` (512), "
          "`samples` per pixel (4), `exposure` (stops: the PNG shows radiance x 2^exposure; the EXR keeps it as an "
          "attribute)",
          [](Options& o) -> std::vector<CameraOptions>& { return o.cameras; }, get_camera, camera_table, "cameras"),
      table_array_key<LightOptions>(
          "light",
          "point source: `name`, `position`, `intensity_cd` (isotropic) or `ies` (IESNA LM-63 file, type C), "
          "`multiplier` (1), `nadir` (its 0 degree direction, [0,0,-1]), `c0` (its C0 plane, [1,0,0]); white",
          [](Options& o) -> std::vector<LightOptions>& { return o.scene.lights; }, get_light, light_table, "lights"),
      table_array_key<GridOptions>(
          "grid",
          "`name`, `origin`, `u`, `v` (edges of the rectangle), `nu`, `nv` (points, at cell centres; 10), `normal` "
          "(u x v), `samples` (gathering rays per point, 4096): NAME.csv and NAME.png of irradiance and illuminance",
          [](Options& o) -> std::vector<GridOptions>& { return o.grids; }, get_grid, grid_table, "grids"),
  };
}

#undef SET
#undef GET

// A printed value as TOML writes it inline.
std::string inline_toml(const toml::node& node) {
  std::ostringstream out;
  if (const toml::table* t = node.as_table()) out << (t->empty() ? "{}" : "(a table)");
  else if (const toml::array* a = node.as_array()) out << (a->empty() ? "[]" : "(an array)");
  else if (const auto d = node.value_exact<double>()) out << fmt::format("{}", *d);  // shortest exact form
  else if (const auto text = node.value_exact<std::string>()) out << '"' << *text << '"';
  else node.visit([&](const auto& v) { out << v; });
  return out.str();
}

}  // namespace

const char* to_string(SolverMethod m) {
  switch (m) {
    case SolverMethod::hierarchical: return "hierarchical";
    case SolverMethod::multipath: return "multipath";
    case SolverMethod::classic: return "classic";
  }
  return "?";
}

const std::vector<ConfigKey>& config_keys() {
  static const std::vector<ConfigKey> table = make_table();
  return table;
}

const ConfigKey* find_config_key(const std::string& key) {
  static const std::map<std::string, const ConfigKey*> index = [] {
    std::map<std::string, const ConfigKey*> m;
    for (const ConfigKey& k : config_keys()) m[k.key] = &k;
    return m;
  }();
  const auto it = index.find(key);
  return it == index.end() ? nullptr : it->second;
}

std::string config_keys_markdown() {
  const Options defaults;
  std::string out = "| key | default | meaning |\n|---|---|---|\n";
  for (const ConfigKey& k : config_keys()) {
    const toml::array value = k.get(defaults);
    const std::string shown = value.empty() ? "none" : "`" + inline_toml(*value.get(0)) + "`";
    const bool tables = k.key == "camera" || k.key == "grid" || k.key == "light";
    out += fmt::format("| `{}` | {} | {} |\n", tables ? "[[" + k.key + "]]" : k.key, shown, k.meaning);
  }
  return out;
}

}  // namespace mpath
