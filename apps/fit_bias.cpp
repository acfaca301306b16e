// fit_bias: panel-metrics CSV → bias model weights YAML (DESIGN.md), and a table on stdout.
// --nested also judges the choice of a model out of sample: every form × {none, huber} is a
// candidate, chosen in each outer fold by inner cross-validation on that fold's training rows.
#include <glog/logging.h>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "args.h"
#include "io/atomic_file.h"
#include "io/csv.h"
#include "io/metrics_csv.h"
#include "io/sha256.h"
#include "io/temp_files.h"
#include "io/weights_yaml.h"
#include "model/bias_model.h"
#include "model/fit_groups.h"
#include "model/select.h"

namespace {

using namespace depthbias;

constexpr char kUsage[] =
    "usage: fit_bias --in metrics.csv --out weights.yaml [options]\n"
    "Fits the bias model per (light, preset) with Ceres and an L2 prior, cross-validated;\n"
    "writes the weights YAML and prints a table. Options (default):\n"
    "  --in FILE            panel-metrics CSV (required)\n"
    "  --out FILE           weights YAML (required)\n"
    "  --model NAME         auto|disp_knots|disp_tan|disp_scale|paper6 (auto: the form and\n"
    "                       loss, huber or none, of lowest pooled held-out RMSE, leaving a\n"
    "                       test point out; chosen again inside every cross-validation fold)\n"
    "  --lambda L           L2 prior strength, >= 0 (0.001)\n"
    "  --loss NAME          auto|none|huber|cauchy|soft_l1, with a named model (auto)\n"
    "  --loss-scale M       where the robust loss departs from the square [m], > 0 (1)\n"
    "  --group-by KEYS      comma list of light, preset, emitter (light,preset)\n"
    "  --cv SCHEMES         comma list of point (leave a test point out), distance,\n"
    "                       angle (leave an off-axis angle out), or none\n"
    "                       (point,distance,angle)\n"
    "  --weight-valid       weight rows by their valid pixels (off)\n"
    "  --focal-px F         f of disparity-space forms [px], > 0 (640)\n"
    "  --baseline-m B       B of disparity-space forms [m], > 0 (0.095)\n"
    "  --prior N=MEAN:S     a prior on weight N, strength S >= 0 (none; repeatable)\n"
    "  --nested             judge the choice of model by nested cross-validation (off)\n"
    "  --cv-out FILE        held-out error of every row under every scheme (none)\n"
    "  --coverage K         print, per distance and scheme, the share of held-out truths\n"
    "                       below corrected - K*sigma (off)\n"
    "  --margins on|off     off: no residual model, no weighting, no near guard (on)\n";

std::vector<std::string> Split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  for (std::string item; std::getline(ss, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

int Fail(const std::string& what) {
  std::cerr << "fit_bias: " << what << "\n";
  return apps::kExitError;
}

}  // namespace

int main(int argc, char** argv) {
  // Ceres logs through glog (22 lines of residual warnings before an error): the tool speaks
  // for itself, in one line.
  FLAGS_minloglevel = google::GLOG_FATAL;
  FLAGS_logtostderr = true;
  google::InitGoogleLogging(argv[0]);
  io::InstallSignalCleanup();
  std::string in, out, cv_out;
  bool nested = false;
  double coverage_k = -1.0;
  model::FitGroupsParams params;
  std::string model_name = "auto";
  try {
    for (apps::Args args(argc, argv); args.Next();) {
      const std::string& a = args.flag();
      if (args.IsHelp()) return apps::PrintHelp(kUsage);
      auto value = [&] { return args.Value(); };
      constexpr double kTiny = 1e-300;
      if (a == "--in") in = value();
      else if (a == "--out") out = value();
      else if (a == "--model") model_name = value();
      else if (a == "--lambda") params.fit.lambda = args.Number(false, 0);
      else if (a == "--loss-scale") params.fit.loss_scale_m = args.Number(false, kTiny);
      else if (a == "--focal-px") params.fit.focal_px = args.Number(false, kTiny);
      else if (a == "--baseline-m") params.fit.baseline_m = args.Number(false, kTiny);
      else if (a == "--cv-out") cv_out = value();
      else if (a == "--weight-valid") params.fit.weight_by_valid_pixels = true;
      else if (a == "--nested") nested = true;
      else if (a == "--coverage") coverage_k = args.Number(false, 0);
      else if (a == "--margins") {
        const std::string v = value();
        if (v != "on" && v != "off") throw std::invalid_argument("--margins " + v + " (on|off)");
        params.fit.margins.enabled = v == "on";
      }
      else if (a == "--group-by") params.group_by = Split(value());
      else if (a == "--loss") {
        const std::string v = value();
        if (!model::ParseLoss(v, &params.fit.loss)) throw std::invalid_argument("--loss " + v);
      } else if (a == "--cv") {
        params.cv.clear();
        for (const auto& s : Split(value())) {
          model::CvScheme scheme;
          if (!model::ParseCvScheme(s, &scheme)) throw std::invalid_argument("--cv " + s);
          params.cv.push_back(scheme);
        }
      } else if (a == "--prior") {
        const std::string v = value();
        const auto eq = v.find('='), colon = v.find(':');
        if (eq == std::string::npos || colon == std::string::npos || colon < eq)
          throw std::invalid_argument("--prior expects name=mean:strength, got '" + v + "'");
        params.fit.priors.push_back(
            {v.substr(0, eq), apps::FlagNumber(a, v.substr(eq + 1, colon - eq - 1), false,
                                               -apps::kNoLimit),
             apps::FlagNumber(a, v.substr(colon + 1), false, 0)});
      } else {
        throw std::invalid_argument("unknown argument '" + a + "'");
      }
    }
    if (in.empty() || out.empty()) throw std::invalid_argument("--in and --out are required");
    if (model_name == "auto") params.select = model::SelectionCandidates(params.fit);
    else params.fit.model = model_name;
    if (nested) params.nested_candidates = model::DefaultCandidates(params.fit);
    std::string why;
    if (!params.IsValid(&why)) throw std::invalid_argument(why);
  } catch (const std::exception& e) {
    return Fail(std::string(e.what()) + " (see fit_bias --help)");
  }

  std::vector<records::PanelMetrics> rows;
  std::string sha;
  try {
    io::CheckOutputs({out, cv_out}, {in});
    io::CheckOutputFile(out);  // before the work, not after it
    if (!cv_out.empty()) io::CheckOutputFile(cv_out);
    rows = io::ReadMetricsCsv(in);
    sha = io::Sha256File(in);
  } catch (const io::IoError& e) {
    return Fail(e.what());
  } catch (const std::bad_alloc&) {
    return Fail(in + ": out of memory while reading it");
  }
  model::FitReport report;
  {
    const apps::Ticker ticker("fit_bias: fitting " + std::to_string(rows.size()) + " rows");
    report = model::FitGroups(rows, params);
  }
  if (!report.success) return Fail(in + ": " + report.message);

  for (const auto& w : report.warnings) std::cerr << "fit_bias: warning: " << w << "\n";
  records::BiasWeights weights = model::ToWeights(report, params);
  weights.input_file = in;
  weights.input_sha256 = sha;
  weights.tool = "fit_bias";
  weights.tool_version = DEPTHBIAS_VERSION;
  try {
    const model::BiasModel check(weights);  // what a reader of these weights would refuse
  } catch (const std::exception& e) {
    return Fail(in + ": the fit gives weights without physical meaning: " + e.what());
  }
  std::vector<std::pair<std::string, std::string>> files = {
      {out, io::FormatWeightsYaml(weights)}};
  if (!cv_out.empty()) {
    // Held-out error of every row under every scheme: which recordings the model cannot explain.
    std::vector<std::vector<std::string>> cells;
    for (const auto& g : report.groups) {
      for (const auto& cv : g.cv) {
        for (size_t i = 0; i < g.group.rows.size(); ++i) {
          const auto& r = rows[g.group.rows[i]];
          cells.push_back({r.bag, g.group.Label(), model::CvSchemeName(cv.scheme),
                           io::CsvNumber(r.distance_m), io::CsvNumber(r.angle_deg), r.emitter,
                           io::CsvNumber(r.median_m - r.distance_m),
                           io::CsvNumber(i < cv.errors_m.size() ? cv.errors_m[i] : NAN),
                           io::CsvNumber(i < cv.std_m.size() ? cv.std_m[i] : NAN)});
        }
      }
    }
    files.push_back({cv_out, io::FormatCsv({"bag", "group", "scheme", "distance_m", "angle_deg",
                                            "emitter", "bias_m", "heldout_error_m",
                                            "heldout_std_m"},
                                           cells)});
  }
  try {
    io::WriteFilesAtomic(files);  // both or neither
  } catch (const io::IoError& e) {
    return Fail(e.what());
  }
  std::fputs(model::FormatFitTable(report, params).c_str(), stdout);
  if (coverage_k >= 0) std::fputs(model::FormatCoverageTable(report, coverage_k).c_str(), stdout);
  std::cerr << "fit_bias: " << report.groups.size() << " groups from " << report.rows_used
            << " rows (" << report.rows_skipped << " not ok, skipped) \u2192 " << out << "\n";
  // Rows that failed upstream were left out of the fit: outputs written, some rows failed.
  return report.rows_skipped > 0 ? apps::kExitRowsFailed : apps::kExitOk;
}
