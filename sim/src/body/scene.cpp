// TOML -> Scene. Every value is checked where it is read; every key not read is reported as unknown.
#include "pmfrag/body/scene.hpp"

#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace pmfrag {

std::string Selection::describe() const {
  switch (kind) {
    case Kind::all: return "all particles";
    case Kind::top_row: return "the top row";
    case Kind::bottom_row: return "the bottom row";
    case Kind::region: return "region " + region.describe();
    case Kind::phase: return "phase '" + name + "'";
    case Kind::body: return "body '" + name + "'";
  }
  return "?";
}

namespace {

// One table being read: remembers which keys were used so the rest can be reported as unknown. Every key
// asked for is also reported to `asked` (if given) under its documented name (docs/scenes.md): arrays of
// tables as "body[]", every region as "region".
class Tab {
 public:
  Tab(const toml::table& t, std::string path, const std::string& file, std::set<std::string>* asked = nullptr,
      std::string doc = "")
      : t_(t), path_(std::move(path)), file_(file), asked_(asked), doc_(std::move(doc)) {}

  /// The same table, documented under another name (a region wherever it appears).
  Tab& documented_as(std::string doc) {
    doc_ = std::move(doc);
    return *this;
  }

  std::string key_path(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

  [[noreturn]] void fail_at(const toml::node* n, const std::string& key, const std::string& msg) const {
    std::ostringstream s;
    const auto line = n ? n->source().begin.line : t_.source().begin.line;
    s << file_;
    if (line > 0)
      s << ":" << line;
    else
      s << " (--set)";
    s << ": key '" << key_path(key) << "': " << msg;
    throw SceneError(s.str());
  }

  const toml::node* get(const std::string& key) {
    used_.insert(key);
    if (asked_) asked_->insert(doc_key(key));
    return t_.get(key);
  }
  bool has(const std::string& key) const { return t_.contains(key); }

  const toml::node& require(const std::string& key) {
    const toml::node* n = get(key);
    if (!n) fail_at(nullptr, key, "missing (required)");
    return *n;
  }

  double number(const toml::node& n, const std::string& key) const {
    auto v = n.value<double>();
    if (!n.is_number() || !v) fail_at(&n, key, "expected a number");
    if (!std::isfinite(*v)) fail_at(&n, key, "must be finite (got " + std::to_string(*v) + ")");
    return *v;
  }
  double number(const std::string& key) { return number(require(key), key); }
  double number(const std::string& key, double fallback) {
    const toml::node* n = get(key);
    return n ? number(*n, key) : fallback;
  }
  double positive(const std::string& key, double fallback = NAN) {
    const toml::node* n = get(key);
    if (!n && std::isnan(fallback)) fail_at(nullptr, key, "missing (required)");
    const double v = n ? number(*n, key) : fallback;
    if (!(v > 0.0)) fail_at(n, key, "must be positive (got " + std::to_string(v) + ")");
    return v;
  }
  long integer(const toml::node& n, const std::string& key) const {
    if (!n.is_integer()) fail_at(&n, key, "expected a whole number");
    return static_cast<long>(*n.value<int64_t>());
  }
  long integer(const std::string& key) { return integer(require(key), key); }
  std::string string(const std::string& key, const std::string& fallback = "\x01") {
    const toml::node* n = get(key);
    if (!n) {
      if (fallback == "\x01") fail_at(nullptr, key, "missing (required)");
      return fallback;
    }
    if (!n->is_string()) fail_at(n, key, "expected a string");
    return *n->value<std::string>();
  }
  bool boolean(const std::string& key, bool fallback) {
    const toml::node* n = get(key);
    if (!n) return fallback;
    if (!n->is_boolean()) fail_at(n, key, "expected true or false");
    return *n->value<bool>();
  }
  Vec3 vector(const toml::node& n, const std::string& key, int dim) const {
    const toml::array* a = n.as_array();
    if (!a || (a->size() != static_cast<std::size_t>(dim) && a->size() != 3))
      fail_at(&n, key, "expected an array of " + std::to_string(dim) + " numbers");
    Vec3 v = Vec3::Zero();
    for (std::size_t i = 0; i < a->size(); ++i) v[static_cast<Eigen::Index>(i)] = number((*a)[i], key);
    if (dim == 2 && a->size() == 3 && v.z() != 0.0) fail_at(&n, key, "a 2-D scene has no z component");
    return v;
  }
  Vec3 vector(const std::string& key, int dim) { return vector(require(key), key, dim); }

  Tab sub(const std::string& key) {
    const toml::node& n = require(key);
    if (!n.is_table()) fail_at(&n, key, "expected a table");
    return Tab(*n.as_table(), key_path(key), file_, asked_, doc_key(key));
  }
  /// A table at `path` (for messages) that is documented as `doc`.
  Tab sub_of(const toml::node& n, const std::string& path, const std::string& doc) const {
    if (!n.is_table()) fail_at(&n, path.substr(path_.empty() ? 0 : path_.size() + 1), "expected a table");
    return Tab(*n.as_table(), path, file_, asked_, doc);
  }
  // An array of tables ([[key]]); absent = empty.
  std::vector<Tab> tables(const std::string& key) {
    std::vector<Tab> out;
    const toml::node* n = get(key);
    if (!n) return out;
    const toml::array* a = n->as_array();
    if (!a) fail_at(n, key, "expected an array of tables ([[" + key + "]])");
    for (std::size_t i = 0; i < a->size(); ++i) {
      if (!(*a)[i].is_table()) fail_at(&(*a)[i], key, "expected a table");
      out.emplace_back(*(*a)[i].as_table(), key_path(key) + "[" + std::to_string(i) + "]", file_, asked_,
                       doc_key(key) + "[]");
    }
    return out;
  }

  /// Reports the first key that was never read.
  void done() const {
    for (auto&& [k, v] : t_) {
      const std::string key(k.str());
      if (!used_.count(key)) {
        std::ostringstream s;
        const auto line = v.source().begin.line;
        s << file_;
        if (line > 0)
          s << ":" << line;
        else
          s << " (--set)";
        s << ": key '" << key_path(key) << "': unknown key";
        throw SceneError(s.str());
      }
    }
  }
  const toml::table& table() const { return t_; }
  std::string doc_key(const std::string& key) const { return doc_.empty() ? key : doc_ + "." + key; }

 private:
  const toml::table& t_;
  std::string path_;
  const std::string& file_;
  std::set<std::string>* asked_;
  std::string doc_;
  std::set<std::string> used_;
};

Region read_region(Tab t, int dim) {
  t.documented_as("region");
  Region r;
  const std::string kind = t.string("kind");
  if (kind == "rect" || kind == "box") {
    if ((kind == "rect") != (dim == 2))
      t.fail_at(t.get("kind"), "kind", "'" + kind + "' does not fit a " + std::to_string(dim) + "-D scene (use " +
                                           (dim == 2 ? "rect" : "box") + ")");
    r.kind = kind == "rect" ? Region::Kind::rect : Region::Kind::box;
    r.min = t.vector("min", dim);
    r.max = t.vector("max", dim);
    if (!((r.max - r.min).head(dim).array() > 0.0).all()) t.fail_at(t.get("max"), "max", "must exceed min in every direction");
  } else if (kind == "disc" || kind == "sphere") {
    if ((kind == "disc") != (dim == 2))
      t.fail_at(t.get("kind"), "kind", "'" + kind + "' does not fit a " + std::to_string(dim) + "-D scene (use " +
                                           (dim == 2 ? "disc" : "sphere") + ")");
    r.kind = kind == "disc" ? Region::Kind::disc : Region::Kind::sphere;
    r.center = t.vector("center", dim);
    r.radius = t.positive("radius");
  } else {
    t.fail_at(t.get("kind"), "kind", "unknown region kind '" + kind + "' (rect, disc, box, sphere)");
  }
  t.done();
  return r;
}

Selection read_selection(Tab& parent, const std::string& key, int dim) {
  const toml::node& n = parent.require(key);
  Selection s;
  if (n.is_string()) {
    if (*n.value<std::string>() != "all") parent.fail_at(&n, key, "expected \"all\" or a table");
    return s;
  }
  Tab t = parent.sub_of(n, parent.key_path(key), parent.doc_key(key));
  int given = 0;
  if (t.has("row")) {
    ++given;
    const std::string row = t.string("row");
    if (row == "top")
      s.kind = Selection::Kind::top_row;
    else if (row == "bottom")
      s.kind = Selection::Kind::bottom_row;
    else
      t.fail_at(t.get("row"), "row", "expected \"top\" or \"bottom\"");
  }
  if (t.has("region")) {
    ++given;
    s.kind = Selection::Kind::region;
    s.region = read_region(t.sub("region"), dim);
  }
  if (t.has("phase")) {
    ++given;
    s.kind = Selection::Kind::phase;
    s.name = t.string("phase");
  }
  if (t.has("body")) {
    ++given;
    s.kind = Selection::Kind::body;
    s.name = t.string("body");
  }
  if (given != 1) parent.fail_at(&n, key, "give exactly one of row, region, phase, body");
  t.done();
  return s;
}

LatticeKind lattice_kind(Tab& t) {
  const std::string k = t.string("lattice");
  if (k == "greenspan_plate") return LatticeKind::greenspan_plate;
  if (k == "triangular") return LatticeKind::triangular;
  if (k == "hcp") return LatticeKind::hcp;
  if (k == "fcc") return LatticeKind::fcc;
  t.fail_at(t.get("lattice"), "lattice", "unknown lattice '" + k + "' (greenspan_plate, triangular, hcp, fcc)");
}

BodySpec read_body(Tab t, int dim, std::size_t index) {
  BodySpec b;
  b.name = t.string("name", "body" + std::to_string(index + 1));
  b.lattice = lattice_kind(t);
  b.r0 = t.positive("r0", 0.2);
  if (b.lattice == LatticeKind::greenspan_plate && b.r0 != 0.2)
    t.fail_at(t.get("r0"), "r0", "the Greenspan plate is defined for r0 = 0.2 cm only (use lattice = \"triangular\")");
  if (t.has("shape")) b.shape = read_region(t.sub("shape"), dim);
  if (const toml::node* n = t.get("origin")) b.origin = t.vector(*n, "origin", dim);
  if (const toml::node* n = t.get("sites")) {
    const toml::array* a = n->as_array();
    if (!a || a->size() != static_cast<std::size_t>(dim)) t.fail_at(n, "sites", "expected " + std::to_string(dim) + " whole numbers");
    std::array<int, 3> s{1, 1, 1};
    for (std::size_t i = 0; i < a->size(); ++i) {
      const long v = t.integer((*a)[i], "sites");
      if (v < 1 || v > 100000) t.fail_at(n, "sites", "each count must be in 1..100000");
      s[i] = static_cast<int>(v);
    }
    b.sites = s;
  }
  if (b.lattice != LatticeKind::greenspan_plate && !b.sites && b.shape.kind == Region::Kind::all)
    t.fail_at(nullptr, "shape", "a " + std::string(dim == 2 ? "triangular" : "close-packed") +
                                   " body needs a shape or sites = [...] (and origin)");
  if (b.sites && !b.origin) t.fail_at(t.get("sites"), "sites", "sites = [...] needs origin = [...]");
  if (const toml::node* n = t.get("holes")) {
    const toml::array* a = n->as_array();
    if (!a) t.fail_at(n, "holes", "expected an array of regions");
    for (std::size_t i = 0; i < a->size(); ++i)
      b.holes.push_back(
          read_region(t.sub_of((*a)[i], t.key_path("holes") + "[" + std::to_string(i) + "]", "region"), dim));
  }
  if (const toml::node* n = t.get("void_sites")) {
    if (const toml::array* a = n->as_array()) {
      for (auto& v : *a) b.void_sites.push_back(static_cast<int>(t.integer(v, "void_sites")));
    } else if (n->is_table()) {
      Tab v = t.sub("void_sites");
      const long first = v.integer("first"), step = v.integer("step"), count = v.integer("count");
      if (first < 1 || step < 1 || count < 1 || count > 10000000)
        v.fail_at(nullptr, "first", "first, step and count must be positive");
      for (long k = 0; k < count; ++k) b.void_sites.push_back(static_cast<int>(first + step * k));
      v.done();
    } else {
      t.fail_at(n, "void_sites", "expected an array of site numbers or {first, step, count}");
    }
  }
  for (Tab s : t.tables("slits")) {
    Segment seg;
    // A slit is a segment in the xy plane; in 3-D it cuts through the whole thickness, so [x, y] suffices.
    seg.from = s.vector("from", 2);
    seg.to = s.vector("to", 2);
    if ((seg.to - seg.from).norm() <= 0.0) s.fail_at(s.get("to"), "to", "a slit needs two distinct ends");
    s.done();
    b.slits.push_back(seg);
  }
  b.phase = t.string("phase", "");
  t.done();
  return b;
}

PhaseSpec read_phase(Tab t, int dim, std::size_t index, double r0) {
  PhaseSpec ph;
  ph.name = t.string("name", "phase" + std::to_string(index + 1));
  const long p = t.integer("p"), q = t.integer("q");
  try {
    validate_exponents(static_cast<int>(std::clamp(p, -1000000L, 1000000L)), static_cast<int>(std::clamp(q, -1000000L, 1000000L)));
  } catch (const std::invalid_argument& e) {
    t.fail_at(t.get(p < 1 ? "p" : "q"), p < 1 ? "p" : "q", e.what());
  }
  ph.p = static_cast<int>(p);
  ph.q = static_cast<int>(q);
  if (t.has("G") || t.has("H") || t.has("mass")) {
    ph.derived = false;
    ph.G = t.positive("G");
    ph.H = t.positive("H");
    ph.mass = t.positive("mass");
  } else if (const toml::node* n = t.get("block")) {
    const Vec3 v = t.vector(*n, "block", 3);
    if (!(v.array() >= r0).all()) t.fail_at(n, "block", "every side must be at least r0 = " + std::to_string(r0) + " cm");
    ph.block = Block{v.x(), v.y(), v.z()};
  }
  if (t.has("region")) ph.region = read_region(t.sub("region"), dim);
  t.done();
  return ph;
}

// Applies one "a.b.c=value" override to the document.
void apply_override(toml::table& doc, const std::string& item) {
  const auto eq = item.find('=');
  if (eq == std::string::npos || eq == 0) throw SceneError("--set '" + item + "': expected key=value");
  // Keys as messages print them (body[0].holes[1].kind) or dotted (body.0.holes.1.kind).
  std::string key;
  for (const char c : item.substr(0, eq)) {
    if (c == '[')
      key += '.';
    else if (c != ']')
      key += c;
  }
  const std::string text = item.substr(eq + 1);
  toml::table parsed;
  try {
    parsed = toml::parse("v = " + text);
  } catch (const toml::parse_error&) {
    parsed = toml::table{{"v", text}};  // a bare word: take it as a string
  }
  std::vector<std::string> parts;
  std::stringstream ss(key);
  for (std::string part; std::getline(ss, part, '.');) parts.push_back(part);
  toml::table* t = &doc;
  for (std::size_t i = 0; i + 1 < parts.size(); ++i) {
    toml::node* n = t->get(parts[i]);
    if (!n) {
      t->insert(parts[i], toml::table{});
      n = t->get(parts[i]);
    }
    if (toml::array* a = n->as_array()) {  // [[x]] arrays: x.0.key
      char* end = nullptr;
      const long idx = std::strtol(parts[i + 1].c_str(), &end, 10);
      if (*end || idx < 0 || static_cast<std::size_t>(idx) >= a->size() || !(*a)[static_cast<std::size_t>(idx)].is_table())
        throw SceneError("--set '" + item + "': '" + parts[i + 1] + "' is not an index into '" + parts[i] + "'");
      t = (*a)[static_cast<std::size_t>(idx)].as_table();
      ++i;
      if (i + 1 >= parts.size()) throw SceneError("--set '" + item + "': needs a key after the index");
      continue;
    }
    t = n->as_table();
    if (!t) throw SceneError("--set '" + item + "': '" + parts[i] + "' is not a table");
  }
  t->insert_or_assign(parts.back(), *parsed.get("v"));
}

}  // namespace

Scene parse_scene(const std::string& text, const std::string& file, const std::vector<std::string>& overrides,
                  std::set<std::string>* keys_asked) {
  toml::table doc;
  try {
    doc = toml::parse(text, file);
  } catch (const toml::parse_error& e) {
    std::ostringstream s;
    s << file << ":" << e.source().begin.line << ": " << e.description();
    throw SceneError(s.str());
  }
  for (const auto& o : overrides) apply_override(doc, o);

  Scene sc;
  sc.file = file;
  sc.source = text;
  sc.overrides = overrides;
  Tab top(doc, "", file, keys_asked);
  sc.title = top.string("title", "");

  // Dimension from the first body's lattice.
  auto body_tabs = top.tables("body");
  if (body_tabs.empty()) top.fail_at(nullptr, "body", "a scene needs at least one [[body]]");
  {
    Tab probe = body_tabs.front();
    const LatticeKind k = lattice_kind(probe);
    sc.dim = (k == LatticeKind::hcp || k == LatticeKind::fcc) ? 3 : 2;
  }
  for (std::size_t i = 0; i < body_tabs.size(); ++i) {
    sc.bodies.push_back(read_body(body_tabs[i], sc.dim, i));
    const LatticeKind k = sc.bodies.back().lattice;
    if (((k == LatticeKind::hcp || k == LatticeKind::fcc) ? 3 : 2) != sc.dim)
      body_tabs[i].fail_at(body_tabs[i].get("lattice"), "lattice", "all bodies must have the same dimension");
    if (sc.bodies.back().r0 != sc.bodies.front().r0)
      body_tabs[i].fail_at(body_tabs[i].get("r0"), "r0", "all bodies must share one lattice spacing r0");
    for (std::size_t j = 0; j < i; ++j)
      if (sc.bodies[j].name == sc.bodies[i].name)
        body_tabs[i].fail_at(body_tabs[i].get("name"), "name", "duplicate body name '" + sc.bodies[i].name + "'");
  }
  const double r0 = sc.bodies.front().r0;

  auto phase_tabs = top.tables("phase");
  if (phase_tabs.empty()) top.fail_at(nullptr, "phase", "a scene needs at least one [[phase]] (the material)");
  for (std::size_t i = 0; i < phase_tabs.size(); ++i) {
    sc.phases.push_back(read_phase(phase_tabs[i], sc.dim, i, r0));
    for (std::size_t j = 0; j < i; ++j)
      if (sc.phases[j].name == sc.phases[i].name)
        phase_tabs[i].fail_at(phase_tabs[i].get("name"), "name", "duplicate phase name '" + sc.phases[i].name + "'");
  }
  auto phase_exists = [&](const std::string& n) {
    for (const auto& p : sc.phases)
      if (p.name == n) return true;
    return false;
  };
  for (std::size_t i = 0; i < sc.bodies.size(); ++i) {
    auto& b = sc.bodies[i];
    if (b.phase.empty()) {
      b.phase = sc.phases.front().name;
    } else if (!phase_exists(b.phase)) {
      body_tabs[i].fail_at(body_tabs[i].table().get("phase"), "phase", "no [[phase]] named '" + b.phase + "'");
    }
  }

  for (Tab t : top.tables("interface")) {
    InterfaceSpec in;
    const toml::node& n = t.require("phases");
    const toml::array* a = n.as_array();
    if (!a || a->size() != 2 || !(*a)[0].is_string() || !(*a)[1].is_string())
      t.fail_at(&n, "phases", "expected two phase names");
    in.a = *(*a)[0].value<std::string>();
    in.b = *(*a)[1].value<std::string>();
    for (const auto& nm : {in.a, in.b})
      if (!phase_exists(nm)) t.fail_at(&n, "phases", "no [[phase]] named '" + nm + "'");
    in.scale = t.positive("scale", 1.0);
    if (t.has("G") || t.has("H") || t.has("p") || t.has("q")) {
      in.explicit_law = true;
      in.law = PairLaw{static_cast<int>(t.integer("p")), static_cast<int>(t.integer("q")), t.positive("G"), t.positive("H")};
      try {
        in.law.validate();
      } catch (const std::invalid_argument& e) {
        t.fail_at(t.get("q"), "q", e.what());
      }
    }
    t.done();
    sc.interfaces.push_back(in);
  }

  if (top.has("pair")) {
    Tab t = top.sub("pair");
    PairSpec p;
    const std::string model = t.string("model", "bonded");
    if (model == "bonded")
      p.model = PairModel::bonded;
    else if (model == "cutoff")
      p.model = PairModel::cutoff;
    else
      t.fail_at(t.get("model"), "model", "expected \"bonded\" or \"cutoff\" (got \"" + model + "\")");
    p.cutoff_r0 = t.number("cutoff", 1.7);
    if (!(p.cutoff_r0 > 1.0) || p.cutoff_r0 > 3.0) t.fail_at(t.get("cutoff"), "cutoff", "D / r0 must be in (1, 3]");
    p.r_min_r0 = t.number("r_min", 0.0);
    if (p.r_min_r0 < 0.0 || p.r_min_r0 >= 1.0) t.fail_at(t.get("r_min"), "r_min", "r_min / r0 must be in [0, 1)");
    p.contact = t.boolean("contact", true);
    const std::string precision = t.string("precision", "double");
    if (precision == "float")
      p.single_precision = true;
    else if (precision != "double")
      t.fail_at(t.get("precision"), "precision", "expected \"double\" or \"float\" (got \"" + precision + "\")");
    t.done();
    sc.pair = p;
  }

  for (Tab t : top.tables("kinematic")) {
    KinematicSpec k;
    k.select = read_selection(t, "select", sc.dim);
    k.velocity = t.vector("velocity", sc.dim);
    t.done();
    sc.kinematic.push_back(k);
  }
  for (Tab t : top.tables("impactor")) {
    ImpactorSpec im;
    im.body = t.string("body");
    bool found = false;
    for (const auto& b : sc.bodies) found = found || b.name == im.body;
    if (!found) t.fail_at(t.get("body"), "body", "no [[body]] named '" + im.body + "'");
    im.velocity = t.vector("velocity", sc.dim);
    t.done();
    sc.impactors.push_back(im);
  }
  if (top.has("gravity")) {
    Tab t = top.sub("gravity");
    sc.gravity = t.vector("g", sc.dim);
    t.done();
  }
  if (top.has("damping")) {
    Tab t = top.sub("damping");
    sc.damping = DampingSpec{t.positive("gamma")};
    t.done();
  }
  if (top.has("greenspan_alpha")) {
    Tab t = top.sub("greenspan_alpha");
    sc.greenspan_alpha = t.boolean("enabled", true);
    t.done();
  }

  {
    Tab t = top.sub("time");
    const toml::node& dt = t.require("dt");
    if (dt.is_string()) {
      const std::string mode = *dt.value<std::string>();
      if (mode != "auto" && mode != "adaptive")
        t.fail_at(&dt, "dt", "expected a step in seconds, \"auto\" or \"adaptive\" (got \"" + mode + "\")");
      sc.time.auto_dt = mode == "auto";
      sc.time.adaptive = mode == "adaptive";
    } else {
      sc.time.dt = t.number(dt, "dt");
      if (!(sc.time.dt > 0.0)) t.fail_at(&dt, "dt", "must be positive (got " + std::to_string(sc.time.dt) + ")");
    }
    sc.time.safety = t.number("safety", 0.5);
    if (!(sc.time.safety > 0.0 && sc.time.safety <= 1.0)) t.fail_at(t.get("safety"), "safety", "must be in (0, 1]");
    sc.time.end = t.positive("end");
    if (t.has("dt_max")) {
      if (!sc.time.adaptive) t.fail_at(t.get("dt_max"), "dt_max", "only with dt = \"adaptive\"");
      sc.time.dt_max = t.positive("dt_max");
    }
    t.done();
  }
  if (top.has("output")) {
    Tab t = top.sub("output");
    sc.output.every = t.positive("every", 1e-4);
    sc.output.checkpoint_every = t.number("checkpoint_every", 0.0);
    if (sc.output.checkpoint_every < 0.0) t.fail_at(t.get("checkpoint_every"), "checkpoint_every", "must be >= 0");
    const std::string precision = t.string("precision", "double");
    if (precision != "double" && precision != "single")
      t.fail_at(t.get("precision"), "precision", "must be \"double\" or \"single\" (got \"" + precision + "\")");
    sc.output.single_precision = precision == "single";
    if (const toml::node* g = t.get("gzip")) {
      const long level = t.integer(*g, "gzip");
      if (level < 0 || level > 9) t.fail_at(g, "gzip", "must be a level from 0 (none) to 9 (got " + std::to_string(level) + ")");
      sc.output.gzip_level = static_cast<int>(level);
    }
    if (const toml::node* f = t.get("fields")) {
      const toml::array* list = f->as_array();
      if (!list) t.fail_at(f, "fields", "must be a list of field names, e.g. [\"position\", \"velocity\"]");
      bool position = false, velocity = false;
      for (const toml::node& e : *list) {
        const auto name = e.value<std::string>();
        if (name && *name == "position") position = true;
        else if (name && *name == "velocity") velocity = true;
        else t.fail_at(&e, "fields", "knows \"position\" and \"velocity\" (got " + (name ? "\"" + *name + "\"" : std::string("a non-string")) + ")");
      }
      if (!position) t.fail_at(f, "fields", "must hold \"position\": fragments, export and render read positions");
      sc.output.velocity = velocity;
    }
    t.done();
  }
  top.done();
  return sc;
}

std::string Scene::recorded_text() const {
  std::string t = source;
  if (!overrides.empty()) {
    t += "\n# --set overrides applied:\n";
    for (const auto& o : overrides) t += "# " + o + "\n";
  }
  return t;
}

Scene read_scene(const std::string& path, const std::vector<std::string>& overrides) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SceneError(path + ": cannot open scene file");
  std::ostringstream s;
  s << in.rdbuf();
  return parse_scene(s.str(), path, overrides);
}

}  // namespace pmfrag
