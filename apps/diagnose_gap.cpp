// diagnose_gap: where a real metrics table departs from the simulator, which registered effect
// explains it, how far the gap shrinks with it (lib/gap); writes DIR/gap.json and DIR/report.md.
// --cases: the withheld-effect proof instead (each effect simulated at two sizes, diagnosed with
// the base model), a Markdown table on stdout (and DIR/cases.md with --out).
#include <glog/logging.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <initializer_list>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <thread>
#include <vector>

#include "args.h"
#include "memory.h"
#include "gap/cases.h"
#include "gap/report.h"
#include "pipeline/gap_cache.h"
#include "io/atomic_file.h"
#include "io/metrics_csv.h"
#include "io/sha256.h"
#include "io/temp_files.h"
#include "sim/config_yaml.h"

namespace {

using namespace depthbias;
namespace fs = std::filesystem;

constexpr char kUsage[] =
    "usage: diagnose_gap --real REAL.csv --out DIR\n"
    "       diagnose_gap --cases [--field FIELD.csv] [--out DIR]\n"
    "Holds a real panel-metrics table against the simulator run on the same cells: where the\n"
    "gap lies, which registered effect explains it, how far it shrinks (in sample and held\n"
    "out). Writes DIR/gap.json and DIR/report.md, all or none. --cases proves the method on\n"
    "tables made with known effects under placement scatter (docs/gap/cases.md): a table on\n"
    "stdout and in DIR/cases.md (each case's gap.json in DIR/cases/). Options (default):\n"
    "  --real FILE          the real panel-metrics CSV (required without --cases)\n"
    "  --out DIR            output folder (required without --cases)\n"
    "  --protocol FILE      protocol YAML: scene, distance meaning (config/protocol_paper.yaml,\n"
    "                       from the working folder, share/depthbias or <source>/build)\n"
    "  --sensor FILE        sensor YAML, or builtin (the protocol's sensor file)\n"
    "  --candidates LIST    all, or registry effects separated by commas (all)\n"
    "  --holdout H          distance, point, light=V or preset=V (distance)\n"
    "  --seed S             seed of the simulation (1; --cases: tables at S + 999 + i,\n"
    "                       tables without effect at 2000 + 20(S - 1) + i, on a user's\n"
    "                       design at 10^9 + 20(S - 1) + i)\n"
    "  --frames N           simulated frames per cell, 1 to 100000 (10)\n"
    "  --threads N          cells simulated in parallel, 1 to 256 (all cores)\n"
    "  --cache DIR          keep the table's simulations in DIR, and take them from there\n"
    "                       when the same cells, protocol, sensor, seed, frames and\n"
    "                       candidates come again with this build: the same outputs, byte\n"
    "                       for byte, without most of the time (none: simulate every run)\n"
    "  --min-effect-shrink P  an effect is kept only if the outer folds' selections, simulated,\n"
    "                       remove P % of the calibrated base's held-out gap, noise\n"
    "                       included (10)\n"
    "  --min-own-shrink P   and leaving it out of them brings back P % of an outer fold's\n"
    "                       calibrated gap, on average over the folds (10)\n"
    "  --min-moved-shrink P, --min-own-moved-shrink P\n"
    "                       or the same two shares of the gap in the metrics they move\n"
    "                       reach P % (20, 30)\n"
    "  --joint-window       effects that move the panel's window through the measured\n"
    "                       depth read it at their joint depth, not each at its own (off)\n"
    "  --lateral-phase P    the valid share of effects that move the window read with\n"
    "                       each test point's panel moved sideways by a draw within ±P px\n"
    "                       of its own, 0 to 10 (0.5; 0: the nominal angles)\n"
    "  --case NAME          --cases: only this case (as named in the table's first column;\n"
    "                       repeatable; \"no effect\" for the 20 null tables, \"no effect,\n"
    "                       user's unit\" for 20 of 32 rows)\n"
    "  --field FILE         --cases: also judge this table of field bags (panel_extract on\n"
    "                       scripts/make_field_campaign.py's bags, offset -0.25 px)\n"
    "  --inject-into FILE   --cases: also judge effects injected by their physics into this\n"
    "                       real table, at 1.5 and 0.5 times its own limits (repeatable;\n"
    "                       cases named after the file: \"STEM + disparity_offset (1.5 × its\n"
    "                       limit)\")\n"
    "  --inject-times LIST  --inject-into: the multiples of a limit injected, plain decimals\n"
    "                       separated by commas, each in (0, 10] and once (1.5,0.5); below 1\n"
    "                       an effect may go unseen, from 1 on it must be selected as itself\n"
    "A table of more than 1024 rows is refused (each distinct cell is about a hundred\n"
    "simulations). Rows the sensor cannot stand for are left out and listed in gap.json's\n"
    "rows_skipped (exit 1): a preset that is not a D455 preset, a light and preset the sensor\n"
    "file does not list, a distance outside its range, an angle outside its field of view.\n";

struct BadInput : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The default protocol, wherever the tool runs from: the working folder's config/, else
// share/depthbias/config/ beside the tool (installed, or the build tree's link to config/).
std::string DefaultProtocol() {
  const std::string name = "protocol_paper.yaml";
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec).parent_path();
  for (const fs::path& dir : {fs::path("config"), exe / ".." / "share" / "depthbias" / "config"})
    if (fs::exists(dir / name, ec)) return (dir / name).string();
  return (fs::path("config") / name).string();
}

// The label a real table's injected cases are named after: its file name without extension.
std::string TableLabel(const std::string& csv) {
  const std::string name = io::BaseName(csv);
  return name.substr(0, name.rfind('.'));
}

}  // namespace

int main(int argc, char** argv) {
  apps::KeepLargeBlocksForReuse();  // the simulator's histograms: about a tenth of the run time
  FLAGS_minloglevel = google::GLOG_FATAL;  // Ceres logs through glog
  io::InstallSignalCleanup();
  std::string real_csv, out_dir, protocol_file = DefaultProtocol(), sensor_file, cache_dir;
  std::vector<std::string> inject_csvs;  // --inject-into
  std::vector<double> inject_times{1.5, 0.5};  // --inject-times
  bool times_given = false;
  bool cases = false;
  std::vector<std::string> only_cases;  // --case
  double frames = 10, threads = std::max(1u, std::thread::hardware_concurrency());
  gap::DiagnoseParams params;
  sim::SimParams base;
  try {
    for (apps::Args args(argc, argv); args.Next();) {
      const std::string& a = args.flag();
      if (args.IsHelp()) return apps::PrintHelp(kUsage);
      if (a == "--real") real_csv = args.Value();
      else if (a == "--out") out_dir = args.Value();
      else if (a == "--protocol") protocol_file = args.Value();
      else if (a == "--sensor") sensor_file = args.Value();
      else if (a == "--candidates") params.candidates = args.Value();
      else if (a == "--holdout") {
        std::string why;
        if (!gap::ParseHoldout(args.Value(), &params.holdout, &why)) throw BadInput(why);
      } else if (a == "--seed") base.seed = static_cast<std::uint64_t>(args.Number(true, 0, 9e15));
      else if (a == "--frames") frames = args.Number(true, 1, 1e5);
      else if (a == "--threads") threads = args.Number(true, 1, 256);
      else if (a == "--cache") cache_dir = args.Value();
      else if (a == "--cases") cases = true;
      else if (a == "--field") real_csv = args.Value();
      else if (a == "--inject-into") inject_csvs.push_back(args.Value());
      else if (a == "--inject-times") {
        // Multiples of a limit, separated by commas: each a plain decimal in (0, 10], once.
        const std::string list = args.Value();
        times_given = true;
        inject_times.clear();
        std::stringstream in(list);
        for (std::string item; std::getline(in, item, ',');) {
          const bool plain = !item.empty() && item.find_first_not_of("0123456789.") ==
                                                  std::string::npos &&
                             std::count(item.begin(), item.end(), '.') <= 1 && item.back() != '.';
          const double v = plain ? std::strtod(item.c_str(), nullptr) : NAN;
          if (!(v > 0 && v <= 10))
            throw BadInput("--inject-times: '" + item + "' is not a multiple in (0, 10]");
          for (double before : inject_times)
            if (gap::RealInjectionCaseName("", "", before) == gap::RealInjectionCaseName("", "", v))
              throw BadInput("--inject-times: '" + item + "' is given twice");
          inject_times.push_back(v);
        }
        if (inject_times.empty() || list.back() == ',')
          throw BadInput("--inject-times: '" + list + "' is not a list of multiples in (0, 10]");
      }
      else if (a == "--case") only_cases.push_back(args.Value());
      else if (a == "--joint-window") params.fit.joint_window = true;
      else if (a == "--lateral-phase")
        params.simulate.lateral_phase_px = args.Number(false, 0, 10);
      else if (a == "--min-effect-shrink") params.min_effect_shrink_pct = args.Number(false, 0, 99.9);
      else if (a == "--min-own-shrink") params.min_own_shrink_pct = args.Number(false, 0, 99.9);
      else if (a == "--min-moved-shrink") params.min_moved_shrink_pct = args.Number(false, 0, 99.9);
      else if (a == "--min-own-moved-shrink")
        params.min_own_moved_shrink_pct = args.Number(false, 0, 99.9);
      else throw BadInput("unknown argument '" + a + "' (see diagnose_gap --help)");
    }
    params.simulate.frames = static_cast<int>(frames);
    params.simulate.threads = static_cast<int>(threads);
    if (!cases && !inject_csvs.empty())
      throw BadInput("--inject-into goes with --cases (see diagnose_gap --help)");
    if (inject_csvs.empty() && times_given)
      throw BadInput("--inject-times goes with --inject-into (see diagnose_gap --help)");
    if (!cases && (real_csv.empty() || out_dir.empty()))
      throw BadInput("--real REAL.csv and --out DIR are required (see diagnose_gap --help)");
    std::string why, named_sensor;
    if (!sim::ParseProtocolYaml(io::ReadFile(protocol_file), &base.protocol, &named_sensor, &why))
      throw BadInput(protocol_file + ": " + why);
    if (sensor_file.empty() && !named_sensor.empty())
      sensor_file = (fs::path(protocol_file).parent_path() / named_sensor).string();
    if (!sensor_file.empty() && sensor_file != "builtin" &&
        !sim::ParseSensorYaml(io::ReadFile(sensor_file), &base.sensor, &why))
      throw BadInput(sensor_file + ": " + why);
    if (!cache_dir.empty()) {  // a folder, or one to be made
      std::error_code ec;
      if (fs::exists(cache_dir, ec) && !fs::is_directory(cache_dir, ec))
        throw BadInput("--cache: " + cache_dir + " is not a folder");
      try {  // a build that cannot read its own files keeps nothing, and runs as without
        params.simulate_design = pipeline::SimulationsKeptIn(
            cache_dir,
            pipeline::SimulationsOrigin(protocol_file,
                                        sensor_file == "builtin" ? "" : sensor_file),
            [](const std::string& note) { std::cerr << "diagnose_gap: note: " << note << "\n"; });
      } catch (const std::exception& e) {
        std::cerr << "diagnose_gap: note: simulations not kept: " << e.what() << "\n";
      }
    }
    if (!params.IsValid(&why)) throw BadInput(why);
    std::vector<gap::Candidate> candidates;
    if (!gap::SelectCandidates(params.candidates, &candidates, &why))
      throw BadInput("--candidates: " + why);
    // Outputs before any work: an existing file or a link to the input as DIR is refused here.
    const std::string json = out_dir.empty() ? "" : (fs::path(out_dir) / "gap.json").string();
    const std::string md = out_dir.empty() ? "" : (fs::path(out_dir) / "report.md").string();
    const std::string cases_md = out_dir.empty() ? "" : (fs::path(out_dir) / "cases.md").string();
    if (!out_dir.empty())
      io::CheckOutputSet(out_dir, cases ? std::vector<std::string>{"cases.md"}
                                        : std::vector<std::string>{"gap.json", "report.md"},
                         [&] {
                           std::vector<std::string> inputs{real_csv, protocol_file, sensor_file};
                           inputs.insert(inputs.end(), inject_csvs.begin(), inject_csvs.end());
                           return inputs;
                         }(),
                         4e6);

    if (cases) {  // tables at seeds S + 999 + i, the null suites at gap::NullTableSeed(S)
      const std::vector<gap::WithheldCase> all = gap::DefaultWithheldCases();
      std::vector<int> only;  // --case: those named (their seeds as in the whole suite)
      std::vector<std::string> only_real;  // --inject-into's cases named
      bool nulls_too = only_cases.empty(), unit_nulls_too = only_cases.empty();
      for (const std::string& name : only_cases) {
        if (name == "no effect" || name == "no effect, user's unit") {
          (name == "no effect" ? nulls_too : unit_nulls_too) = true;
          continue;
        }
        const auto it = std::find_if(all.begin(), all.end(),
                                     [&](const gap::WithheldCase& c) { return c.name == name; });
        const bool real = gap::IsRealInjectionCase(name);
        if (it == all.end() && !real) throw BadInput("--case: no case named '" + name + "'");
        if (real && inject_csvs.empty())
          throw BadInput("--case '" + name + "' needs --inject-into REAL.csv");
        if (real) {  // one of the names the tables and multiples given make, before any work
          bool known = false;
          for (const std::string& csv : inject_csvs)
            for (const std::string& n : gap::RealInjectionCaseNames(TableLabel(csv), inject_times))
              known = known || name == n;
          if (!known)
            throw BadInput("--case: no case named '" + name + "' on the --inject-into tables at "
                           "the --inject-times multiples");
          only_real.push_back(name);
        }
        if (it != all.end()) only.push_back(static_cast<int>(it - all.begin()));
      }
      std::vector<gap::CaseOutcome> outcomes;
      if (only_cases.empty() || !only.empty())
        outcomes = gap::RunWithheldCases(base, all, params, base.seed + 999, only);
      if (!real_csv.empty()) {  // a campaign of field bags through panel_extract (--field)
        std::vector<records::PanelMetrics> rows = io::ReadMetricsCsv(real_csv);
        gap::ScreenRows(gap::DesignRulesOf(base.sensor), &rows);
        const gap::DiagnoseResult r = gap::Diagnose(rows, base, params);
        if (!r.success) throw BadInput(real_csv + ": " + r.message);
        gap::ReportContext ctx{io::BaseName(real_csv), "", protocol_file, sensor_file, base.seed,
                               DEPTHBIAS_VERSION};
        const std::string json = gap::GapJson(r, params, ctx);
        outcomes.push_back(gap::JudgeCase(json, gap::FieldCampaignCase(), rows));
        outcomes.back().gap_json = json;
      }
      // Real tables, effects injected (--inject-into): all their cases, or those named.
      for (const std::string& csv : (only_cases.empty() || !only_real.empty())
                                        ? inject_csvs
                                        : std::vector<std::string>{}) {
        std::vector<records::PanelMetrics> rows = io::ReadMetricsCsv(csv);
        gap::ScreenRows(gap::DesignRulesOf(base.sensor), &rows);
        for (gap::CaseOutcome& o : gap::RunRealInjectionCases(base, rows, TableLabel(csv), params,
                                                                  only_real, inject_times))
          outcomes.push_back(std::move(o));
      }
      // A case named that its table leaves out (its limit that way lies beyond its grid).
      for (const std::string& name : only_real)
        if (std::none_of(outcomes.begin(), outcomes.end(),
                         [&](const gap::CaseOutcome& o) { return o.truth.name == name; }))
          std::fprintf(stderr,
                       "diagnose_gap: '%s' not injected: on its table that effect's limit lies "
                       "beyond its grid\n",
                       name.c_str());
      auto null_suite = [&](bool run, bool unit) {
        return run ? gap::RunWithheldCases(base, gap::NullCases(20, unit), params,
                                           gap::NullTableSeed(base.seed, unit))
                   : std::vector<gap::CaseOutcome>{};
      };
      const std::vector<gap::CaseOutcome> nulls = null_suite(nulls_too, false);
      const std::vector<gap::CaseOutcome> unit_nulls = null_suite(unit_nulls_too, true);
      const std::string table = gap::FormatCases(outcomes, nulls, unit_nulls);
      std::fputs(table.c_str(), stdout);
      if (!out_dir.empty()) {  // the table, and each case's gap.json in DIR/cases/
        fs::create_directories(fs::path(out_dir) / "cases");
        for (const std::vector<gap::CaseOutcome>* list :
             std::initializer_list<const std::vector<gap::CaseOutcome>*>{&outcomes, &nulls,
                                                                         &unit_nulls})
          for (const gap::CaseOutcome& o : *list) {
            std::string name = o.truth.name.empty() ? "field" : o.truth.name;
            for (char& ch : name)
              if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
            if (!o.gap_json.empty())
              io::WriteFileAtomic((fs::path(out_dir) / "cases" / (name + ".json")).string(),
                                  o.gap_json);
          }
        io::WriteFileAtomic(cases_md, table);
      }
      return apps::kExitOk;
    }
    const gap::DesignRules rules = gap::DesignRulesOf(base.sensor);
    const std::string text = io::ReadFile(real_csv, 16ull << 20);  // 1024 rows: < 1 MB
    const long lines = std::count(text.begin(), text.end(), '\n') +
                       (!text.empty() && text.back() != '\n' ? 1 : 0);
    if (lines - 1 > rules.max_rows)  // the header
      throw BadInput(real_csv + ": " + std::to_string(lines - 1) + " rows, more than the " +
                     std::to_string(rules.max_rows) + " a diagnosis takes");
    std::vector<records::PanelMetrics> rows = io::ParseMetricsCsv(text, real_csv);
    gap::ScreenRows(rules, &rows);
    if (rules.scenarios.empty())
      std::cerr << "diagnose_gap: note: the sensor lists no scenario: every light and preset "
                   "has its fallback noise\n";
    const gap::DiagnoseResult r = gap::Diagnose(rows, base, params);
    if (!r.success) throw BadInput(real_csv + ": " + r.message);
    gap::ReportContext ctx{io::BaseName(real_csv), io::Sha256File(real_csv), protocol_file,
                           sensor_file.empty() ? "builtin" : sensor_file, base.seed,
                           DEPTHBIAS_VERSION};
    fs::create_directories(out_dir);
    io::WriteFilesAtomic({{json, gap::GapJson(r, params, ctx)},
                          {md, gap::GapMarkdown(r, params, ctx)}});
    std::fputs(gap::GapSummary(r).c_str(), stdout);
    if (!r.message.empty()) std::cerr << "diagnose_gap: note: " << r.message << "\n";
    for (const std::string& skipped : r.design.skipped)
      std::cerr << "diagnose_gap: " << real_csv << ": " << skipped << " (left out)\n";
    return r.design.skipped.empty() ? apps::kExitOk : apps::kExitRowsFailed;
  } catch (const std::exception& e) {  // usage, input or output: nothing written
    std::cerr << "diagnose_gap: " << e.what() << "\n";
    return apps::kExitError;
  }
}
