#include "pmfrag/run/sweep.hpp"

#include "pmfrag/model/material.hpp"
#include "pmfrag/body/scene.hpp"

#include <toml++/toml.h>

#include <cstdio>
#include <filesystem>
#include <sstream>

namespace pmfrag {

namespace {

[[noreturn]] void fail(const std::string& file, const toml::node* n, const std::string& key, const std::string& what) {
  std::ostringstream s;
  s << file << ":";
  if (n && n->source().begin.line > 0) s << n->source().begin.line << ":";
  s << " key '" << key << "': " << what;
  throw SceneError(s.str());
}

// A TOML value as the text a --set item takes.
std::string as_set_value(const std::string& file, const std::string& key, const toml::node& n) {
  std::ostringstream s;
  if (auto v = n.value<double>(); v && (n.is_floating_point() || n.is_integer())) {
    char b[40];
    std::snprintf(b, sizeof b, "%.17g", *v);
    return b;
  }
  if (n.is_boolean()) return *n.value<bool>() ? "true" : "false";
  if (n.is_string()) {
    std::string quoted(1, '"');  // built by appending: GCC 12 warns (-Wrestrict) on "literal" + string here
    quoted += *n.value<std::string>();
    quoted += '"';
    return quoted;
  }
  if (n.is_array()) {
    s << toml::toml_formatter{*n.as_array()};
    return s.str();
  }
  fail(file, &n, key, "expected a number, string, boolean or array");
}

}  // namespace

SweepSpec read_sweep_spec(const std::string& path) {
  SweepSpec spec;
  spec.file = path;
  toml::table top;
  try {
    top = toml::parse_file(path);
  } catch (const toml::parse_error& e) {
    std::ostringstream s;
    s << path << ":" << e.source().begin.line << ": " << e.description();
    throw SceneError(s.str());
  }
  for (const auto& [k, v] : top)
    if (k != "base" && k != "pairs" && k != "set" && k != "vary")
      fail(path, &v, std::string(k.str()), "unknown key (expected base, pairs, set, vary)");
  const toml::node* base = top.get("base");
  if (!base || !base->is_string()) fail(path, base, "base", "the base scene file is required (a string)");
  spec.base = (std::filesystem::path(path).parent_path() / *base->value<std::string>()).lexically_normal().string();
  const toml::node* pairs = top.get("pairs");
  if (!pairs) fail(path, nullptr, "pairs", "required: \"all\" or a list like [[3, 5], [7, 14]]");
  if (pairs->is_string()) {
    if (*pairs->value<std::string>() != "all") fail(path, pairs, "pairs", "the only word allowed is \"all\"");
    spec.pairs = fig3_grid();
  } else if (const toml::array* a = pairs->as_array()) {
    for (const auto& item : *a) {
      const toml::array* pq = item.as_array();
      if (!pq || pq->size() != 2 || !(*pq)[0].is_integer() || !(*pq)[1].is_integer())
        fail(path, &item, "pairs", "each pair is [p, q] with two integers");
      const int p = static_cast<int>(*(*pq)[0].value<long long>()), q = static_cast<int>(*(*pq)[1].value<long long>());
      if (p < 1 || q <= p) fail(path, &item, "pairs", "needs 1 <= p < q");
      spec.pairs.push_back({p, q});
    }
    if (spec.pairs.empty()) fail(path, pairs, "pairs", "is empty");
  } else {
    fail(path, pairs, "pairs", "expected \"all\" or a list of [p, q]");
  }
  if (const toml::node* set = top.get("set")) {
    const toml::table* t = set->as_table();
    if (!t) fail(path, set, "set", "expected a table of key = value");
    for (const auto& [k, v] : *t) spec.set.push_back(std::string(k.str()) + "=" + as_set_value(path, "set." + std::string(k.str()), v));
  }
  if (const toml::node* vary = top.get("vary")) {
    const toml::table* t = vary->as_table();
    if (!t) fail(path, vary, "vary", "expected a table of key = [values]");
    for (const auto& [k, v] : *t) {
      const std::string key = "vary." + std::string(k.str());
      const toml::array* a = v.as_array();
      if (!a || a->empty()) fail(path, &v, key, "expected a non-empty list of values");
      std::vector<std::string> values;
      for (const auto& x : *a) values.push_back(as_set_value(path, key, x));
      spec.vary.emplace_back(std::string(k.str()), values);
    }
  }
  return spec;
}

std::vector<SweepCase> sweep_cases(const SweepSpec& spec, std::size_t phases) {
  std::vector<std::vector<std::string>> combos{{}};
  std::vector<std::vector<std::string>> labels{{}};
  for (const auto& [key, values] : spec.vary) {
    std::vector<std::vector<std::string>> next, next_labels;
    for (std::size_t c = 0; c < combos.size(); ++c)
      for (const auto& v : values) {
        auto s = combos[c];
        s.push_back(key + "=" + v);
        next.push_back(s);
        auto l = labels[c];
        l.push_back(key + "=" + v);
        next_labels.push_back(l);
      }
    combos = next, labels = next_labels;
  }
  std::vector<SweepCase> out;
  for (const auto& [p, q] : spec.pairs)
    for (std::size_t c = 0; c < combos.size(); ++c) {
      SweepCase k;
      k.p = p, k.q = q;
      char name[32];
      std::snprintf(name, sizeof name, "p%d_q%d", p, q);
      k.name = name;
      for (const auto& l : labels[c]) {
        std::string safe = l;
        for (char& ch : safe)
          if (ch == '/' || ch == ' ' || ch == '"' || ch == '[' || ch == ']' || ch == ',') ch = '_';
        k.name += '_';
        k.name += safe;
      }
      for (std::size_t ph = 0; ph < phases; ++ph) {
        k.overrides.push_back("phase." + std::to_string(ph) + ".p=" + std::to_string(p));
        k.overrides.push_back("phase." + std::to_string(ph) + ".q=" + std::to_string(q));
      }
      k.overrides.insert(k.overrides.end(), spec.set.begin(), spec.set.end());
      k.overrides.insert(k.overrides.end(), combos[c].begin(), combos[c].end());
      out.push_back(k);
    }
  return out;
}

}  // namespace pmfrag
