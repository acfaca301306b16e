// The withheld cases' criteria (cases.h), read from the gap.json a diagnosis wrote: the proof
// judges what the diagnosis publishes, whichever code made it.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <set>
#include <sstream>

#include "gap/cases.h"
#include "gap/json_read.h"

namespace depthbias::gap {
namespace {

using Json = JsonValue;

// The light of a scenario "light/preset".
std::string LightOf(const std::string& scenario) {
  return scenario.substr(0, scenario.rfind('/'));
}

std::string Num(double v, int digits = 3) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  return buf;
}

// Every string and every object under a value (the cells `unexplained` may name).
void Collect(const Json& v, std::vector<std::string>* strings, std::vector<const Json*>* objects) {
  if (v.type == Json::kString) strings->push_back(v.text);
  if (v.type == Json::kObject) objects->push_back(&v);
  for (const auto& item : v.items) Collect(item, strings, objects);
  for (const auto& [k, item] : v.members) Collect(item, strings, objects);
}

std::string Stem(std::string id) {
  if (id.size() > 4 && id.compare(id.size() - 4, 4, ".bag") == 0) id.resize(id.size() - 4);
  return id;
}

// The rows `unexplained` names: by id (with or without .bag), or by factor cells (an object
// with distance_m, and optionally angle_deg, light, preset, emitter).
std::set<size_t> NamedRows(const Json& u, const std::vector<records::PanelMetrics>& rows) {
  std::vector<std::string> strings;
  std::vector<const Json*> objects;
  Collect(u, &strings, &objects);
  std::set<size_t> named;
  for (const std::string& s : strings)
    for (size_t i = 0; i < rows.size(); ++i)
      if (Stem(s) == Stem(rows[i].bag)) named.insert(i);
  for (const Json* o : objects) {
    const double d = o->Number("distance_m"), a = o->Number("angle_deg");
    if (!std::isfinite(d)) continue;
    const Json* l = o->Find("light");
    const Json* p = o->Find("preset");
    for (size_t i = 0; i < rows.size(); ++i) {
      if (std::fabs(rows[i].distance_m - d) > 1e-6) continue;
      if (std::isfinite(a) && std::fabs(rows[i].angle_deg - a) > 1e-6) continue;
      if (l && l->type == Json::kString && rows[i].light != l->text) continue;
      if (p && p->type == Json::kString && rows[i].preset != p->text) continue;
      named.insert(i);
    }
  }
  return named;
}

// Rows an outside effect makes "right" for `unexplained`, and those it must include (the far
// end of an over-read or of a far step; the test point of a step).
void RightRows(const OutsideEffect& o, const std::vector<records::PanelMetrics>& rows,
               std::set<size_t>* allowed, std::set<size_t>* needed) {
  double far = 0;
  for (const auto& r : rows) far = std::max(far, r.distance_m);
  for (size_t i = 0; i < rows.size(); ++i) {
    const auto& r = rows[i];
    if ((o.kind == OutsideEffect::kFarOverRead || o.kind == OutsideEffect::kFarStep) &&
        r.distance_m >= o.from_distance_m) {
      allowed->insert(i);
      if (r.distance_m == far) needed->insert(i);
    }
    if (o.kind == OutsideEffect::kPointStep && r.light == o.light &&
        r.distance_m == o.distance_m && r.angle_deg == o.angle_deg)
      allowed->insert(i), needed->insert(i);
  }
}

// A far over-read is a law over the whole table: an entry of `unexplained` that gives the median
// bias's law (form ∝ D², its value at the far end within 20 % of the injected one, criterion 2)
// answers it wherever its cells lie.
bool GivesTheLaw(const Json& entry, const OutsideEffect& o,
                 const std::vector<records::PanelMetrics>& rows) {
  if (o.kind != OutsideEffect::kFarOverRead || entry.type != Json::kObject) return false;
  const Json* metric = entry.Find("metric");
  const Json* form = entry.Find("form");
  const double far_end = entry.Number("size_at_far_end");
  if (!metric || metric->type != Json::kString || metric->text != "median_bias_m" || !form ||
      form->type != Json::kString || form->text != "∝ D²" || !std::isfinite(far_end))
    return false;
  double far = 0;
  for (const auto& r : rows) far = std::max(far, r.distance_m);
  const double truth = o.coef * (far / 10) * (far / 10);
  return truth != 0 && std::fabs(far_end - truth) <= 0.2 * std::fabs(truth);
}

// The injected value of a parameter in a scenario ("light/preset"), or the neutral value.
struct Truth {
  double value = NAN;
  bool present = false;
};
Truth TruthIn(const Injection& in, const std::string& scenario, const Axis& axis) {
  const std::string light = scenario.substr(0, scenario.find('/'));
  Truth t;
  t.present = in.only_light.empty() || in.only_light == light;
  if (!t.present) return t.value = axis.neutral, t;
  const auto it = in.params.find(axis.param);
  if (it != in.params.end()) return t.value = it->second, t;
  const sim::EffectInfo* info = sim::FindEffect(in.effect);
  for (const auto& p : info->params)
    if (p.name == axis.param) t.value = p.default_value;
  return t;
}

// A fitted parameter's value in a scenario ("light/preset") from an effect's params: one value,
// or one per light or per scenario.
double ValueIn(const Json& params, const std::string& scenario, const std::string& param) {
  const bool grouped =
      !params.members.empty() && params.members.front().second.type == Json::kObject;
  const Json* group = !grouped                ? &params
                      : params.Find(scenario) ? params.Find(scenario)
                                              : params.Find(LightOf(scenario));
  return group ? group->Number(param) : NAN;
}

// The params of a selected effect in gap.json, or nullptr. With `alone`, where the diagnosis
// selects nothing, those of the effect's fit alone in `effects`: beside the calibration, which
// is all it keeps. (Beside a selection, a law's fit alone also takes what a correlated kept law
// holds: on the field campaign, whose own offset is kept, a depth scale alone fits +5.4 %.)
const Json* FittedParams(const Json& root, const std::string& effect, bool alone = false) {
  const Json* list = root.Find("selected");
  if (alone && (!list || list->empty())) list = root.Find("effects");
  if (list)
    for (const Json& e : list->items)
      if (const Json* name = e.Find("name"); name && name->text == effect) return e.Find("params");
  return nullptr;
}
bool Selected(const Json& root, const std::string& effect) {
  return FittedParams(root, effect) != nullptr;
}

// The nested held-out gaps, mean z² over the cells both tables hold out: the injected table's
// baseline and simulated (g[0], g[1]) and the reference's (g[2], g[3]), all in the injected
// table's units. Each cell's z is in the unit of the outer fold that held it out; the
// reference's is brought over by the ratio of the two folds' units (an injected offset widens
// the noise and the placement scatter by (Z'/Z)², so the two tables' own units differ). Cells
// are matched by their bag. False where either table publishes no nested cells, a bag is not
// one cell's, no cell is common, or a held-out cell has no simulated z (a fold not simulated:
// the published simulated gap is null then).
bool NestedGapsInOneUnit(const Json& root, const Json& reference, double g[4]) {
  const Json* cells = root.Find("cells");
  const Json* ref_cells = reference.Find("cells");
  if (!cells || !ref_cells) return false;
  std::map<std::string, const Json*> ref;  // bag → the reference's nested block
  for (const Json& r : ref_cells->items) {
    const Json* bag = r.Find("bag");
    if (!bag || !ref.emplace(bag->text, r.Find("nested")).second) return false;
  }
  auto get = [](const Json* block, const char* key, const std::string& metric) {
    const Json* o = block->Find(key);
    return o ? o->Number(metric) : NAN;
  };
  // Whether a held-out observation lacks its simulated z.
  auto unsimulated = [&](const Json* block, const std::string& metric) {
    return std::isfinite(get(block, "z_baseline", metric)) &&
           !std::isfinite(get(block, "z_simulated", metric));
  };
  double sum[4] = {0, 0, 0, 0};
  int n = 0;
  std::set<std::string> seen;
  for (const Json& c : cells->items) {
    const Json* bag = c.Find("bag");
    if (!bag || !seen.insert(bag->text).second) return false;
    const Json* nested = c.Find("nested");
    const auto at = ref.find(bag->text);
    const Json* nested0 = at == ref.end() ? nullptr : at->second;
    const Json* units = nested ? nested->Find("unit") : nullptr;
    if (!nested0 || !units) continue;
    for (const auto& [metric, u] : units->members) {
      if (unsimulated(nested, metric) || unsimulated(nested0, metric)) return false;
      const double ratio = get(nested0, "unit", metric) / u.number;
      const double z[4] = {get(nested, "z_baseline", metric), get(nested, "z_simulated", metric),
                           get(nested0, "z_baseline", metric) * ratio,
                           get(nested0, "z_simulated", metric) * ratio};
      if (!std::all_of(z, z + 4, [](double v) { return std::isfinite(v); })) continue;
      for (int i = 0; i < 4; ++i) sum[i] += z[i] * z[i];
      ++n;
    }
  }
  for (int i = 0; i < 4; ++i) g[i] = n ? sum[i] / n : NAN;
  return n > 0;
}

// Whether the limit gap.json publishes for the effect's parameter, in the direction of `value`
// from the neutral one, is at least as far as `value` (no size kept within the grid: it is).
bool LimitCovers(const Json& root, const std::string& effect, const std::string& param,
                 double value, double neutral, std::string* shown) {
  const Json* limits = root.Find("detection_limits");
  const Json* list = limits ? limits->Find("effects") : nullptr;
  if (!list) return false;
  for (const Json& e : list->items) {
    const Json* name = e.Find("effect");
    const Json* p = e.Find("param");
    if (!name || !p || name->text != effect || p->text != param) continue;
    const Json* side = e.Find(value < neutral ? "below" : "above");
    const Json* size = side ? side->Find("size") : nullptr;
    if (!size) return false;
    if (size->type == Json::kNull) return *shown = "no size within the grid", true;
    if (size->type != Json::kNumber) return false;
    *shown = param + " " + Num(size->number);
    return std::fabs(size->number - neutral) >= std::fabs(value - neutral);
  }
  return false;
}

// An entry of `unexplained` by its metric and where it lies.
std::string EntryKey(const Json& entry) {
  const Json* metric = entry.Find("metric");
  const Json* where = entry.Find("where");
  return (metric ? metric->text : "") + "|" + (where ? where->text : "");
}

// The effects a real table's own diagnosis selects, each read again on the injected table:
// selected, and in every scenario of the rows each parameter (one shared value, or one per
// light or scenario) within 20 % of its departure from the neutral value (whole-pixel widths:
// equal). An over-read outside the registry taken by a law the table holds is pinned on that
// law. Returns the first effect not read again so, with its sizes; "" when all are.
std::string ReferenceMoved(const Json& root, const Json& reference,
                           const std::vector<records::PanelMetrics>& rows) {
  const Json* list = reference.Find("selected");
  if (!list) return "";
  std::set<std::string> scenarios;
  for (const auto& r : rows)
    if (r.ok()) scenarios.insert(r.light + "/" + r.preset);
  for (const Json& e : list->items) {
    const Json* name = e.Find("name");
    const Json* before = e.Find("params");
    if (!name || !before) continue;
    const Json* after = FittedParams(root, name->text);
    if (!after) return name->text + " (not selected)";
    for (const Candidate& c : DefaultCandidates()) {
      if (c.effect != name->text) continue;
      for (const Axis& a : c.axes)
        for (const std::string& sc : scenarios) {
          const double was = ValueIn(*before, sc, a.param), now = ValueIn(*after, sc, a.param);
          const double neutral = std::isfinite(a.neutral) ? a.neutral : 0.0;
          const double scale = was != neutral ? std::fabs(was - neutral) : 1.0;
          const bool same = a.discrete ? now == was : std::fabs(now - was) <= 0.2 * scale;
          if (std::isfinite(was) && !(std::isfinite(now) && same))
            return name->text + " (" + sc + " " + a.param + " " + Num(now) + ", " + Num(was) +
                   " before)";
        }
    }
  }
  return "";
}

}  // namespace

CaseOutcome JudgeCase(const std::string& gap_json, const WithheldCase& truth,
                      const std::vector<records::PanelMetrics>& rows,
                      const std::string& reference_json) {
  CaseOutcome o;
  o.truth = truth;
  o.unexplained = "-";
  Json root, reference;
  if (!ParseJson(gap_json, &root) || root.type != Json::kObject) {
    o.why = "gap.json does not parse";
    return o;
  }
  const bool on_reference = !reference_json.empty();
  if (truth.on_real != on_reference) {
    o.why = on_reference ? "a reference given for a simulated case"
                         : "a case on a real table judged without its reference";
    return o;
  }
  if (on_reference &&
      (!ParseJson(reference_json, &reference) || reference.type != Json::kObject)) {
    o.why = "the reference's gap.json does not parse";
    return o;
  }
  auto fail = [&](const std::string& why) { o.why += (o.why.empty() ? "" : "; ") + why; };
  // Selected set.
  std::map<std::string, const Json*> fitted;
  std::map<std::string, std::string> scope;  // "shared", "per_light", "per_scenario"
  if (const Json* sel = root.Find("selected"))
    for (const Json& s : sel->items)
      if (const Json* name = s.Find("name")) {
        o.selected.push_back(name->text);
        fitted[name->text] = s.Find("params");
        if (const Json* sc = s.Find("scope")) scope[name->text] = sc->text;
      }
  std::set<std::string> want, got;
  for (const Injection& in : truth.injected) want.insert(in.effect);
  // On a real table, what its own diagnosis selects (and was not injected) is the table's.
  for (const std::string& e : o.selected)
    if (!on_reference || want.count(e) || !Selected(reference, e)) got.insert(e);
  // An injected effect the table cannot tell from the calibration (a gain on σ_d or on the hole
  // probability, where each scenario's σ_d and p are calibrated) is never selected: it is
  // answered when gap.json names it "one of" with the calibration, with the size it would need
  // (per scenario, in the calibration's scenario order, or one shared value). Beside a selection,
  // it and the selected effects are read in the one fit that holds them all (selection_with),
  // where there is one such effect: a drift's median shift is the offset's to give back.
  std::map<std::string, std::vector<double>> aliased;
  const Json* branch = nullptr;  // the aliased effect's selection_with
  if (const Json* amb = root.Find("ambiguous"))
    for (const Json& a : amb->items) {
      const Json* one = a.Find("one_of");
      const Json* sizes = a.Find("sizes");
      if (!one || !sizes) continue;
      bool calibration = false;
      for (const Json& e : one->items) calibration |= e.text.rfind("calibration:", 0) == 0;
      for (size_t i = 0; calibration && i < one->items.size() && i < sizes->items.size(); ++i) {
        const std::string& name = one->items[i].text;
        if (!want.count(name) || got.count(name)) continue;
        std::vector<double> v;
        std::istringstream words(sizes->items[i].text);
        std::string w;
        while (words >> w) {
          char* end = nullptr;
          const double x = std::strtod(w.c_str(), &end);
          if (end != w.c_str() && *end == '\0') v.push_back(x);
        }
        aliased[name] = v;
        if (const Json* with = a.Find("selection_with")) branch = with;
      }
    }
  std::string on_branch;  // the aliased effect, read in the branch's fit; or ""
  if (aliased.size() == 1 && branch) {
    for (const auto& [effect, params] : branch->members)
      if (fitted.count(effect) || aliased.count(effect)) fitted[effect] = &params;
    if (fitted.count(aliased.begin()->first)) on_branch = aliased.begin()->first;
  }
  std::set<std::string> answered = got;
  for (const auto& [name, v] : aliased) answered.insert(name);
  if (answered != want) fail("selected set differs from the injected set");
  // Sizes, scenario by scenario.
  std::set<std::string> scenarios;
  for (const auto& r : rows)
    if (r.ok()) scenarios.insert(r.light + "/" + r.preset);
  const std::vector<Candidate> all = DefaultCandidates();
  o.max_rel_error = truth.injected.empty() ? NAN : 0.0;
  for (const Injection& in : truth.injected) {
    const Candidate* cand = nullptr;
    for (const Candidate& c : all)
      if (c.effect == in.effect) cand = &c;
    const auto al = aliased.find(in.effect);
    if (cand && al != aliased.end() && cand->axes.size() == 1 && in.effect != on_branch) {
      // Named "one of" with the calibration: the size it would need, scenario by scenario.
      std::vector<std::string> order;
      if (const Json* cal = root.Find("calibration"))
        if (const Json* sc = cal->Find("scenarios"))
          for (const Json& e : sc->items)
            if (const Json* nm = e.Find("scenario")) order.push_back(nm->text);
      const Axis& axis = cand->axes[0];
      const std::vector<double>& v = al->second;
      // One value per light (in the scenarios' order of first sight), where it has that many.
      std::vector<std::string> lights;
      for (const std::string& sc : order)
        if (std::find(lights.begin(), lights.end(), LightOf(sc)) == lights.end())
          lights.push_back(LightOf(sc));
      const bool per_light = v.size() > 1 && v.size() != order.size() && v.size() == lights.size();
      std::string shown;
      double err_max = v.empty() ? INFINITY : 0.0;
      for (size_t i = 0; i < order.size(); ++i) {
        const Truth t = TruthIn(in, order[i], axis);
        const size_t light = static_cast<size_t>(
            std::find(lights.begin(), lights.end(), LightOf(order[i])) - lights.begin());
        const double got_v = v.size() == 1 ? v[0]
                             : per_light   ? v[light]
                             : i < v.size() ? v[i]
                                            : NAN;
        const double scale = std::isfinite(axis.neutral) && t.value != axis.neutral
                                 ? std::fabs(t.value - axis.neutral)
                                 : 1.0;
        const double err = std::isfinite(got_v) && std::isfinite(t.value)
                               ? std::fabs(got_v - t.value) / scale
                               : INFINITY;
        err_max = std::max(err_max, err);
        shown += (shown.empty() ? "" : ", ") + order[i] + " " + axis.param + " " + Num(got_v);
      }
      o.max_rel_error = std::max(o.max_rel_error, err_max);
      o.recovered[in.effect] = "one of {" + in.effect + ", calibration}: " + shown;
      continue;
    }
    const auto it = fitted.find(in.effect);
    if (!cand || it == fitted.end() || !it->second) {
      o.max_rel_error = INFINITY;
      continue;
    }
    const Json& params = *it->second;
    const bool grouped = !params.members.empty() &&
                         params.members.front().second.type == Json::kObject;
    const std::string scope_text = scope.count(in.effect) ? scope[in.effect] : "";
    std::string shown;
    for (const Axis& axis : cand->axes) {
      double scale = 0;
      for (const std::string& sc : scenarios) {
        const Truth t = TruthIn(in, sc, axis);
        if (t.present)
          scale = std::max(scale, std::isfinite(axis.neutral) ? std::fabs(t.value - axis.neutral)
                                                              : std::fabs(t.value));
      }
      if (!(scale > 0)) scale = 1;
      for (const std::string& sc : scenarios) {
        const Truth t = TruthIn(in, sc, axis);
        if (!std::isfinite(t.value)) continue;  // a shape parameter where the effect is absent
        // Per scenario: the scenario's values; per light: its light's.
        const std::string key = params.Find(sc) ? sc : LightOf(sc);
        double got_v = ValueIn(params, sc, axis.param);
        const Json* ref = on_reference ? FittedParams(reference, in.effect, true) : nullptr;
        if (ref && !axis.discrete) {
          // What the injection moved: less the real table's own size of it, as the table's own
          // diagnosis fits it, selected, or alone where it selects nothing (a law below its
          // limit); against one shared answer, the mean of that fit over the scenarios.
          double own = 0;
          for (const std::string& s : grouped ? std::set<std::string>{sc} : scenarios)
            own += ValueIn(*ref, s, axis.param) / (grouped ? 1.0 : scenarios.size());
          // A scale composes by product: (1 + s₀)(1 + s) = 1 + fitted.
          if (std::isfinite(own))
            got_v = in.effect == "depth_scale" ? (1 + got_v) / (1 + own) - 1
                                               : got_v - own + axis.neutral;
        }
        double err = std::fabs(got_v - t.value) / scale;
        if (axis.discrete) err = got_v == t.value ? 0.0 : INFINITY;
        if (!std::isfinite(got_v)) err = INFINITY;
        o.max_rel_error = std::max(o.max_rel_error, err);
        const std::string item = (grouped ? key + " " : "") + axis.param + " " + Num(got_v);
        if (grouped ? shown.find(item) == std::string::npos
                    : shown.find(axis.param) == std::string::npos)
          shown += (shown.empty() ? "" : ", ") + item;
      }
    }
    std::string prefix = grouped ? scope_text + ": " : "";
    std::replace(prefix.begin(), prefix.end(), '_', ' ');
    if (in.effect == on_branch) prefix = "one of {" + in.effect + ", calibration}, beside: ";
    o.recovered[in.effect] = prefix + shown;
  }
  if (!truth.injected.empty() && !(o.max_rel_error <= 0.2))
    fail("a size is off by more than 20 %");
  // The shrink the simulator reproduces, held out: null where the held-out baseline leaves no
  // gap beyond the noise.
  bool published = false;
  if (const Json* how = root.Find("how_far"))
    if (const Json* s = how->Find("shrink_simulated_pct")) {
      published = true;
      if (s->type == Json::kNumber) o.shrink_simulated_pct = s->number;
    }
  bool one_unit = true;
  if (on_reference) {  // the injected part of the nested gap, and what the selection removes
    double g[4];  // B, S, B₀, S₀
    one_unit = NestedGapsInOneUnit(root, reference, g);
    const double part = one_unit ? g[0] - g[2] : NAN;
    o.shrink_simulated_pct = part > 0 ? 100 * ((g[0] - g[1]) - (g[2] - g[3])) / part : NAN;
  }
  if (!truth.injected.empty()) {
    if (!published) fail("no how_far.shrink_simulated_pct");
    else if (!one_unit) fail("the two tables' held-out cells are not read in one unit");
    else if (!std::isfinite(o.shrink_simulated_pct)) fail("no held-out gap beyond noise to shrink");
    else if (o.shrink_simulated_pct < 70) fail("simulated shrink below 70 %");
  }
  // What is left unexplained.
  const Json* u = root.Find("unexplained");
  o.has_unexplained = u && !u->empty();
  std::set<size_t> named;
  if (u) named = NamedRows(*u, rows);
  if (o.has_unexplained) {
    o.unexplained = named.empty() ? "names no row" : std::to_string(named.size()) + " rows";
    if (!named.empty()) {
      std::set<double> d;
      for (size_t i : named) d.insert(rows[i].distance_m);
      o.unexplained += " at ";
      for (double x : d) o.unexplained += Num(x) + " ";
      o.unexplained += "m";
    }
  }
  if (truth.outside.kind != OutsideEffect::kNone) {
    std::set<size_t> allowed, needed;
    RightRows(truth.outside, rows, &allowed, &needed);
    // The law over the whole table, if given; the other entries must name the right cells.
    // On a real table, an entry its own diagnosis gives too (the same metric, where) is the
    // table's, not the over-read's.
    std::set<std::string> own;
    if (const Json* ru = on_reference ? reference.Find("unexplained") : nullptr)
      for (const Json& entry : ru->items) own.insert(EntryKey(entry));
    bool law = false;
    std::set<size_t> rest = named;
    if (u && u->type == Json::kArray) {
      rest.clear();
      for (const Json& entry : u->items) {
        if (GivesTheLaw(entry, truth.outside, rows)) {
          law = true;
          continue;
        }
        if (own.count(EntryKey(entry))) continue;
        const std::set<size_t> n = NamedRows(entry, rows);
        rest.insert(n.begin(), n.end());
      }
    }
    bool inside = law || !rest.empty(), hits = law;
    for (size_t i : rest) {
      inside = inside && allowed.count(i);
      hits = hits || needed.count(i);
    }
    if (!u) fail("no unexplained in gap.json");
    else if (!inside || !hits) fail("unexplained does not name the right cells");
    if (on_reference) {
      const std::string moved = ReferenceMoved(root, reference, rows);
      if (!moved.empty()) fail("the table's own " + moved + " took the over-read");
    }
  }
  // Below the real table's limit: not selecting it is an answer when the published limit says
  // an effect that size could go unseen.
  if (truth.may_go_unseen && got.empty() && truth.injected.size() == 1 &&
      truth.injected[0].params.size() == 1) {
    const Injection& in = truth.injected[0];
    const auto& [param, value] = *in.params.begin();
    double neutral = 0;
    for (const Candidate& c : DefaultCandidates())
      if (c.effect == in.effect && !c.axes.empty() && std::isfinite(c.axes[0].neutral))
        neutral = c.axes[0].neutral;
    std::string shown;
    if (LimitCovers(root, in.effect, param, value, neutral, &shown)) {
      o.why.clear();
      o.max_rel_error = NAN;
      o.recovered[in.effect] = "not selected; could go unseen up to " + shown;
    }
  }
  o.pass = o.why.empty();
  return o;
}

}  // namespace depthbias::gap
