#include "config.h"

#include <toml++/toml.h>

#include <functional>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <thread>

#include "error.h"

namespace mpath {
namespace {

namespace fs = std::filesystem;

// Where a value came from, for messages and for resolving relative paths.
struct ValueSource {
  std::string key;
  std::string where;  // "file:line" or "command line"
  bool from_command_line = false;
  fs::path base_dir;  // relative paths are taken from here
};

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

double in_range(double v, double lo, double hi, const ValueSource& src) {
  if (!(v >= lo && v <= hi)) bad_value(src, fmt::format("expected a value in [{}, {}], got {}", lo, hi, v));
  return v;
}

Rgb get_rgb(const toml::node& node, const ValueSource& src) {
  if (node.is_number()) {
    const double g = get_number(node, src);
    if (g < 0) bad_value(src, "emitted radiance must not be negative");
    return {g, g, g};
  }
  const Vec3 v = get_vec3(node, src);
  if (v.x < 0 || v.y < 0 || v.z < 0) bad_value(src, "emitted radiance must not be negative");
  return {v.x, v.y, v.z};
}

CameraOptions get_camera(const toml::table& table, const ValueSource& parent, size_t index) {
  CameraOptions cam;
  cam.name = fmt::format("camera{}", index);
  for (const auto& [k, node] : table) {
    ValueSource src = parent;
    src.key = fmt::format("{}[{}].{}", parent.key, index, std::string(k.str()));
    const std::string key(k.str());
    if (key == "name") cam.name = get_string(node, src);
    else if (key == "position") cam.position = get_vec3(node, src);
    else if (key == "look_at") cam.look_at = get_vec3(node, src);
    else if (key == "up") cam.up = get_vec3(node, src);
    else if (key == "fov_deg") cam.fov_deg = in_range(get_number(node, src), 1.0, 179.0, src);
    else if (key == "width") cam.width = static_cast<int>(std::min(positive(get_integer(node, src), src), 16384LL));
    else if (key == "height") cam.height = static_cast<int>(std::min(positive(get_integer(node, src), src), 16384LL));
    else if (key == "samples") cam.samples = static_cast<int>(std::min(positive(get_integer(node, src), src), 4096LL));
    else if (key == "exposure") cam.exposure = get_number(node, src);
    else bad_value(src, "unknown key");
  }
  if (length(cam.look_at - cam.position) == 0.0) bad_value(parent, "camera position equals look_at");
  if (length(cross(cam.look_at - cam.position, cam.up)) == 0.0) bad_value(parent, "camera up is parallel to the view direction");
  return cam;
}

using Setter = std::function<void(const toml::node&, const ValueSource&, Options&)>;

const std::map<std::string, Setter>& setters() {
  static const std::map<std::string, Setter> table = {
      {"scene.file", [](auto& n, auto& s, Options& o) { o.scene.file = get_path(n, s); }},
      {"scene.emitters",
       [](auto& n, auto& s, Options& o) {
         const toml::table* t = n.as_table();
         if (!t) bad_value(s, fmt::format("expected a table of material = [r, g, b], got {}", type_name(n)));
         o.scene.emitters.clear();
         for (const auto& [name, value] : *t) {
           ValueSource e = s;
           e.key = s.key + "." + std::string(name.str());
           o.scene.emitters[std::string(name.str())] = get_rgb(value, e);
         }
       }},
      {"scene.two_sided",
       [](auto& n, auto& s, Options& o) {
         const toml::array* a = n.as_array();
         if (!a) bad_value(s, fmt::format("expected an array of material names, got {}", type_name(n)));
         o.scene.two_sided.clear();
         for (const auto& v : *a) o.scene.two_sided.push_back(get_string(v, s));
       }},
      {"scene.mgf_default_sides",
       [](auto& n, auto& s, Options& o) {
         const long long v = get_integer(n, s);
         if (v != 1 && v != 2) bad_value(s, fmt::format("expected 1 or 2, got {}", v));
         o.scene.mgf_default_sides = static_cast<int>(v);
       }},
      {"mesh.max_patch_area",
       [](auto& n, auto& s, Options& o) {
         o.mesh.max_patch_area = get_number(n, s);
         if (o.mesh.max_patch_area < 0) bad_value(s, "expected a positive area (or 0 for automatic)");
       }},
      {"mesh.curve_segments",
       [](auto& n, auto& s, Options& o) {
         o.mesh.curve_segments = static_cast<int>(get_integer(n, s));
         if (o.mesh.curve_segments < 3 || o.mesh.curve_segments > 1024) bad_value(s, "expected an integer in [3, 1024]");
       }},
      {"hierarchy.group_threshold", [](auto& n, auto& s, Options& o) { o.hierarchy.group_threshold = in_range(get_number(n, s), 0.0, 1e9, s); }},
      {"hierarchy.vp_area_ratio", [](auto& n, auto& s, Options& o) { o.hierarchy.vp_area_ratio = in_range(get_number(n, s), 1e-6, 1e9, s); }},
      {"hierarchy.vp_grid",
       [](auto& n, auto& s, Options& o) {
         const long long g = get_integer(n, s);
         if (g < 0 || g > 64 || (g & (g - 1)) != 0) bad_value(s, "expected 0 (automatic) or a power of two up to 64");
         o.hierarchy.vp_grid = static_cast<int>(g);
       }},
      {"hierarchy.max_share", [](auto& n, auto& s, Options& o) { o.hierarchy.max_share = in_range(get_number(n, s), 0.0, 1.0, s); }},
      {"hierarchy.max_depth", [](auto& n, auto& s, Options& o) { o.hierarchy.max_depth = static_cast<int>(in_range(get_integer(n, s), 0, 64, s)); }},
      {"lines.total", [](auto& n, auto& s, Options& o) { o.lines.total = positive(get_integer(n, s), s); }},
      {"lines.root_fraction", [](auto& n, auto& s, Options& o) { o.lines.root_fraction = in_range(get_number(n, s), 0.0, 1.0, s); }},
      {"lines.min_density", [](auto& n, auto& s, Options& o) { o.lines.min_density = in_range(get_number(n, s), 0.0, 1e6, s); }},
      {"lines.box_budget",
       [](auto& n, auto& s, Options& o) { o.lines.box_budget = get_choice(n, s, "budget", {"quotient", "objects"}); }},
      {"lines.seed",
       [](auto& n, auto& s, Options& o) {
         const long long v = get_integer(n, s);
         if (v < 0) bad_value(s, "expected a non-negative integer");
         o.lines.seed = static_cast<unsigned long long>(v);
       }},
      {"lines.sequence",
       [](auto& n, auto& s, Options& o) { o.lines.sequence = get_choice(n, s, "sequence", {"random", "halton"}); }},
      {"first_shot.lines", [](auto& n, auto& s, Options& o) { o.first_shot.lines = positive(get_integer(n, s), s); }},
      {"first_shot.accelerate", [](auto& n, auto& s, Options& o) { o.first_shot.accelerate = get_bool(n, s); }},
      {"first_shot.mode",
       [](auto& n, auto& s, Options& o) { o.first_shot.mode = get_choice(n, s, "mode", {"auto", "local"}); }},
      {"solver.adaptive_lines", [](auto& n, auto& s, Options& o) { o.solver.adaptive_lines = get_bool(n, s); }},
      {"solver.schedule",
       [](auto& n, auto& s, Options& o) { o.solver.schedule = get_choice(n, s, "schedule", {"v-cycle", "top-down"}); }},
      {"solver.method",
       [](auto& n, auto& s, Options& o) { o.solver.method = get_choice(n, s, "method", {"hierarchical", "multipath", "classic"}); }},
      {"solver.iterations", [](auto& n, auto& s, Options& o) { o.solver.iterations = static_cast<int>(std::min(positive(get_integer(n, s), s), 100000LL)); }},
      {"solver.tolerance", [](auto& n, auto& s, Options& o) { o.solver.tolerance = in_range(get_number(n, s), 0.0, 1.0, s); }},
      {"solver.threads", [](auto& n, auto& s, Options& o) { o.solver.threads = static_cast<int>(in_range(get_integer(n, s), 0, 4096, s)); }},
      {"store.dir", [](auto& n, auto& s, Options& o) { o.store.dir = get_path(n, s); }},
      {"store.chunk_lines", [](auto& n, auto& s, Options& o) { o.store.chunk_lines = static_cast<int>(in_range(get_integer(n, s), 256, 1 << 24, s)); }},
      {"store.zstd_level", [](auto& n, auto& s, Options& o) { o.store.zstd_level = static_cast<int>(in_range(get_integer(n, s), 1, 19, s)); }},
      {"output.dir", [](auto& n, auto& s, Options& o) { o.output.dir = get_path(n, s); }},
      {"output.exr", [](auto& n, auto& s, Options& o) { o.output.exr = get_bool(n, s); }},
      {"output.png", [](auto& n, auto& s, Options& o) { o.output.png = get_bool(n, s); }},
      {"camera",
       [](auto& n, auto& s, Options& o) {
         o.cameras.clear();
         if (const toml::table* t = n.as_table()) {
           o.cameras.push_back(get_camera(*t, s, 0));
           return;
         }
         const toml::array* a = n.as_array();
         if (!a || !a->is_array_of_tables()) bad_value(s, "expected [[camera]] tables");
         for (size_t i = 0; i < a->size(); ++i) o.cameras.push_back(get_camera(*a->get(i)->as_table(), s, i));
       }},
  };
  return table;
}

std::string where(const toml::node& node, const fs::path& file) {
  return fmt::format("{}:{}", file.string(), node.source().begin.line);
}

// Applies every value of `table` (recursively), naming unknown keys.
void apply_table(const toml::table& table, const std::string& prefix, const fs::path& file,
                 const std::set<std::string>& cli_keys, Options& options) {
  for (const auto& [k, node] : table) {
    const std::string key = prefix.empty() ? std::string(k.str()) : prefix + "." + std::string(k.str());
    auto it = setters().find(key);
    const bool from_cli = cli_keys.count(key) > 0;
    ValueSource src{key, from_cli ? "command line" : where(node, file), from_cli,
                    from_cli ? fs::current_path() : file.parent_path()};
    if (it != setters().end()) {
      it->second(node, src, options);
    } else if (const toml::table* sub = node.as_table()) {
      apply_table(*sub, key, file, cli_keys, options);
    } else {
      throw InputError(fmt::format("{}: unknown config key '{}'", src.where, key));
    }
  }
}

// Parses the right-hand side of key=value as TOML; a bare word is a string.
toml::table parse_override_value(const std::string& text) {
  try {
    return toml::parse("v = " + text);
  } catch (const toml::parse_error&) {
    toml::table t;
    t.insert("v", text);
    return t;
  }
}

void apply_override(toml::table& root, const std::string& assignment, std::set<std::string>& cli_keys) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    throw InputError(fmt::format("command line: expected key=value, got '{}'", assignment));
  const std::string key = assignment.substr(0, eq);
  toml::table value = parse_override_value(assignment.substr(eq + 1));
  toml::table* node = &root;
  size_t start = 0;
  for (;;) {
    const size_t dot = key.find('.', start);
    const std::string part = key.substr(start, dot == std::string::npos ? std::string::npos : dot - start);
    if (part.empty()) throw InputError(fmt::format("command line: malformed key '{}'", key));
    if (dot == std::string::npos) {
      node->insert_or_assign(part, std::move(*value.get("v")));
      break;
    }
    auto [it, inserted] = node->insert(part, toml::table{});
    node = it->second.as_table();
    if (!node) throw InputError(fmt::format("command line: '{}' is not a table in key '{}'", part, key));
    start = dot + 1;
  }
  cli_keys.insert(key);
}

toml::array vec_to_toml(const Vec3& v) { return toml::array{v.x, v.y, v.z}; }

toml::table options_table(const Options& o) {
  toml::table emitters;
  for (const auto& [name, rgb] : o.scene.emitters) emitters.insert(name, toml::array{rgb[0], rgb[1], rgb[2]});
  toml::array two_sided;
  for (const auto& name : o.scene.two_sided) two_sided.push_back(name);
  toml::array cameras;
  for (const auto& c : o.cameras) {
    cameras.push_back(toml::table{{"name", c.name}, {"position", vec_to_toml(c.position)},
                                  {"look_at", vec_to_toml(c.look_at)}, {"up", vec_to_toml(c.up)},
                                  {"fov_deg", c.fov_deg}, {"width", c.width}, {"height", c.height},
                                  {"samples", c.samples}, {"exposure", c.exposure}});
  }
  toml::table t{
      {"scene", toml::table{{"file", o.scene.file.string()}, {"emitters", emitters}, {"two_sided", two_sided},
                            {"mgf_default_sides", o.scene.mgf_default_sides}}},
      {"mesh", toml::table{{"max_patch_area", o.mesh.max_patch_area}, {"curve_segments", o.mesh.curve_segments}}},
      {"hierarchy", toml::table{{"group_threshold", o.hierarchy.group_threshold},
                                {"vp_area_ratio", o.hierarchy.vp_area_ratio},
                                {"vp_grid", o.hierarchy.vp_grid},
                                {"max_share", o.hierarchy.max_share},
                                {"max_depth", o.hierarchy.max_depth}}},
      {"lines", toml::table{{"total", static_cast<int64_t>(o.lines.total)},
                            {"root_fraction", o.lines.root_fraction},
                            {"box_budget", o.lines.box_budget},
                            {"min_density", o.lines.min_density},
                            {"seed", static_cast<int64_t>(o.lines.seed)},
                            {"sequence", o.lines.sequence}}},
      {"first_shot", toml::table{{"lines", static_cast<int64_t>(o.first_shot.lines)},
                                 {"accelerate", o.first_shot.accelerate},
                                 {"mode", o.first_shot.mode}}},
      {"solver", toml::table{{"method", o.solver.method}, {"iterations", o.solver.iterations},
                             {"tolerance", o.solver.tolerance}, {"threads", o.solver.threads},
                             {"adaptive_lines", o.solver.adaptive_lines}, {"schedule", o.solver.schedule}}},
      {"store", toml::table{{"dir", o.store.dir.string()}, {"chunk_lines", o.store.chunk_lines},
                            {"zstd_level", o.store.zstd_level}}},
      {"output", toml::table{{"dir", o.output.dir.string()}, {"exr", o.output.exr}, {"png", o.output.png}}},
  };
  if (!cameras.empty()) t.insert("camera", cameras);
  return t;
}

}  // namespace

Options load_options(const fs::path& config_path, const std::vector<std::string>& overrides) {
  if (!fs::exists(config_path)) throw InputError(fmt::format("{}: config file not found", config_path.string()));
  const fs::path file = fs::absolute(config_path).lexically_normal();
  toml::table root;
  try {
    root = toml::parse_file(file.string());
  } catch (const toml::parse_error& e) {
    throw InputError(fmt::format("{}:{}: malformed TOML: {}", file.string(), e.source().begin.line,
                                 std::string(e.description())));
  }
  std::set<std::string> cli_keys;
  for (const auto& assignment : overrides) apply_override(root, assignment, cli_keys);

  Options options;
  options.config_file = file;
  // Default folders live beside the config file, like the paths written in it.
  options.store.dir = file.parent_path() / options.store.dir;
  options.output.dir = file.parent_path() / options.output.dir;
  apply_table(root, "", file, cli_keys, options);
  if (options.scene.file.empty()) throw InputError(fmt::format("{}: config key 'scene.file' is required", file.string()));
  return options;
}

std::string options_to_toml(const Options& options) {
  std::ostringstream out;
  out << options_table(options) << "\n";
  return out.str();
}

std::string options_to_json(const Options& options) {
  std::ostringstream out;
  out << toml::json_formatter{options_table(options)};
  return out.str();
}

int effective_threads(const Options& options) {
  if (options.solver.threads > 0) return options.solver.threads;
  return std::max(1u, std::thread::hardware_concurrency());
}

}  // namespace mpath
