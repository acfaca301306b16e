#include "gap/sim_cache.h"

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <sstream>

#include "sim/config_yaml.h"

namespace depthbias::gap {
namespace {

constexpr char kMagic[] = "depthbias gap simulations 1 (little-endian, IEEE 754 binary64)\n";
constexpr std::uint64_t kMaxVector = std::uint64_t{1} << 32;  // values in one stored vector

// A number written so that it reads back to the same bits.
std::string Exact(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// FNV-1a over the bytes: a check that the payload is the one written, not a signature.
std::uint64_t Checksum(const char* p, size_t n) {
  std::uint64_t h = 14695981039346656037ull;
  for (size_t i = 0; i < n; ++i) {
    h ^= static_cast<unsigned char>(p[i]);
    h *= 1099511628211ull;
  }
  return h;
}

bool LittleEndian() {
  const std::uint16_t one = 1;
  unsigned char first;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

class Writer {
 public:
  void U64(std::uint64_t v) { Raw(&v, sizeof v); }
  void F64(double v) { Raw(&v, sizeof v); }
  void Vector(const std::vector<double>& v) {
    U64(v.size());
    Raw(v.data(), v.size() * sizeof(double));
  }
  void Text(const std::string& s) {
    U64(s.size());
    out_ += s;
  }
  std::string& bytes() { return out_; }

 private:
  void Raw(const void* p, size_t n) { out_.append(static_cast<const char*>(p), n); }
  std::string out_;
};

class Reader {
 public:
  Reader(const char* p, size_t n) : p_(p), end_(p + n) {}
  bool U64(std::uint64_t* v) { return Raw(v, sizeof *v); }
  bool F64(double* v) { return Raw(v, sizeof *v); }
  bool Vector(std::vector<double>* v) {
    std::uint64_t n = 0;
    if (!U64(&n) || n > kMaxVector || n * sizeof(double) > Left()) return false;
    v->resize(n);
    return Raw(v->data(), n * sizeof(double));
  }
  bool Text(std::string* s) {
    std::uint64_t n = 0;
    if (!U64(&n) || n > Left()) return false;
    s->assign(p_, n);
    p_ += n;
    return true;
  }
  size_t Left() const { return static_cast<size_t>(end_ - p_); }

 private:
  bool Raw(void* v, size_t n) {
    if (n > Left()) return false;
    if (n) std::memcpy(v, p_, n);
    p_ += n;
    return true;
  }
  const char* p_;
  const char* end_;
};

int GridNodes(const Candidate& c) {
  int n = 1;
  for (const Axis& a : c.axes) n *= static_cast<int>(a.nodes.size());
  return n;
}

}  // namespace

std::string SimulationsKey(const std::string& origin, const sim::SimParams& base,
                           const Design& d, const std::vector<Candidate>& candidates,
                           const SimulateOptions& options) {
  if (origin.empty()) return "";
  // A base with departures of its own is the caller's experiment, not a protocol: not kept.
  if (!base.departures.OnlyEmitter() ||
      base.departures.emitter_gain != sim::Departures{}.emitter_gain)
    return "";
  std::ostringstream k;
  k << "origin " << origin << "\n";
  k << "seed " << base.seed << "\n";
  // Every option but the threads (SimulateOptions: a field added there is added here).
  k << "options frames " << options.frames << " region_margin_px "
    << Exact(options.region_margin_px) << " step_log_sigma " << Exact(options.step_log_sigma)
    << " step_logit_p " << Exact(options.step_logit_p) << " replica " << options.replica
    << " shift_px " << Exact(options.shift_px) << " dither_quantization "
    << options.dither_quantization << " placement_probe " << Exact(options.placement_probe)
    << " lateral_phase_px " << Exact(options.lateral_phase_px) << "\n";
  k << "metrics";
  for (int m : d.metrics) k << " " << m;
  k << "\n";
  for (const sim::Cell& c : d.cells)
    k << "cell " << c.name << " | panel " << c.panel << " | " << Exact(c.distance_m) << " m | "
      << Exact(c.angle_deg) << " deg | " << c.preset << " | emitter " << c.emitter_on << " | "
      << c.light << "\n";
  for (const Candidate& c : candidates) {
    k << "candidate " << c.effect << " range_law " << c.range_law << " moves_window "
      << c.moves_window << "\n";
    for (const Axis& a : c.axes) {
      k << "  axis " << a.param << " nodes";
      for (double v : a.nodes) k << " " << Exact(v);
      k << " neutral " << Exact(a.neutral) << " discrete " << a.discrete << " log_scale "
        << a.log_scale << " reference " << Exact(a.reference) << " bounds " << Exact(a.min_value)
        << " " << Exact(a.max_value) << "\n";
    }
  }
  k << "sensor\n" << sim::FormatSensorYaml(base.sensor, {});
  return k.str();
}

std::string EncodeSimulations(const Simulations& s, const std::string& key) {
  if (!LittleEndian()) return "";
  Writer w;
  w.bytes() = kMagic;
  w.Text(key);
  for (const std::vector<double>* v : {&s.base, &s.depth_m, &s.jac_log_sigma, &s.jac_logit_p,
                                       &s.replica, &s.shifted, &s.moved})
    w.Vector(*v);
  w.F64(s.moved_rel);
  w.U64(static_cast<std::uint64_t>(s.runs));
  w.U64(s.surfaces.size());
  for (const Surface& surf : s.surfaces) {
    w.U64(static_cast<std::uint64_t>(surf.num_nodes));
    w.Vector(surf.table);
  }
  const std::uint64_t sum = Checksum(w.bytes().data(), w.bytes().size());
  w.U64(sum);
  return std::move(w.bytes());
}

bool DecodeSimulations(const std::string& bytes, const std::string& key,
                       const sim::SimParams& base, const Design& d,
                       const std::vector<Candidate>& candidates, Simulations* out,
                       std::string* why) {
  auto fail = [&](const std::string& reason) {
    if (why) *why = reason;
    return false;
  };
  if (!LittleEndian()) return fail("this machine is not little-endian");
  const size_t magic = std::strlen(kMagic);
  if (bytes.size() < magic || bytes.compare(0, magic, kMagic) != 0)
    return fail("not a depthbias simulations file of this format");
  if (bytes.size() < magic + sizeof(std::uint64_t))
    return fail("truncated");
  std::uint64_t sum = 0;
  std::memcpy(&sum, bytes.data() + bytes.size() - sizeof sum, sizeof sum);
  if (Checksum(bytes.data(), bytes.size() - sizeof sum) != sum)
    return fail("its checksum does not match (truncated or altered)");
  Reader r(bytes.data() + magic, bytes.size() - magic - sizeof sum);
  std::string stored_key;
  if (!r.Text(&stored_key)) return fail("truncated key");
  if (stored_key != key) return fail("made for other cells, parameters or program");

  Simulations s;
  for (const sim::Cell& c : d.cells) s.cell_names.push_back(c.name);
  s.metrics = d.metrics;
  s.sensor = ListScenarios(base.sensor, d);
  const size_t obs = d.cells.size() * d.metrics.size();
  const struct {
    std::vector<double>* v;
    const char* name;
    size_t size;
    bool may_be_empty;
  } vectors[] = {{&s.base, "base", obs, false},
                 {&s.depth_m, "depth_m", d.cells.size(), false},
                 {&s.jac_log_sigma, "jac_log_sigma", obs, false},
                 {&s.jac_logit_p, "jac_logit_p", obs, false},
                 {&s.replica, "replica", obs, true},
                 {&s.shifted, "shifted", obs, true},
                 {&s.moved, "moved", obs, true}};
  for (const auto& e : vectors) {
    if (!r.Vector(e.v)) return fail(std::string("truncated at ") + e.name);
    if (e.v->size() != e.size && !(e.may_be_empty && e.v->empty()))
      return fail(std::string(e.name) + " holds " + std::to_string(e.v->size()) +
                  " values, the design " + std::to_string(e.size));
  }
  std::uint64_t runs = 0, n_surfaces = 0;
  if (!r.F64(&s.moved_rel) || !r.U64(&runs) || !r.U64(&n_surfaces))
    return fail("truncated before its surfaces");
  if (n_surfaces != candidates.size())
    return fail(std::to_string(n_surfaces) + " surfaces for " +
                std::to_string(candidates.size()) + " candidates");
  s.runs = static_cast<int>(runs);
  for (const Candidate& cand : candidates) {
    Surface surf;
    surf.candidate = cand;
    std::uint64_t nodes = 0;
    if (!r.U64(&nodes) || !r.Vector(&surf.table)) return fail("truncated at " + cand.effect);
    surf.num_nodes = static_cast<int>(nodes);
    if (nodes != static_cast<std::uint64_t>(GridNodes(cand)) ||
        surf.table.size() != obs * nodes)
      return fail(cand.effect + "'s surface does not fit its grid and the design");
    s.surfaces.push_back(std::move(surf));
  }
  if (r.Left() != 0) return fail("bytes beyond its surfaces");
  *out = std::move(s);
  return true;
}

}  // namespace depthbias::gap
