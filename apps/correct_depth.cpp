// correct_depth: applies a fitted bias model to a panel-metrics CSV.
// Adds per row: predicted_bias_m = b(Z, α) at Z = median_m, α = angle_deg; corrected_m = Z − b;
// predictive_std_m; margin_m = corrected_m − k·predictive_std_m (safe distance); residual_m =
// corrected_m − distance_m. Rows whose status is not ok get empty cells.
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include "args.h"
#include "io/atomic_file.h"
#include "io/csv.h"
#include "io/metrics_csv.h"
#include "io/temp_files.h"
#include "io/weights_yaml.h"
#include "model/bias_model.h"
#include "model/domain.h"

namespace {

constexpr char kUsage[] =
    "usage: correct_depth --weights weights.yaml --in metrics.csv --out corrected.csv [--k 2]\n"
    "Adds per row predicted_bias_m, corrected_m, predictive_std_m, margin_m (corrected_m minus\n"
    "k predictive standard deviations: a distance the target is not nearer than) and\n"
    "residual_m (corrected_m minus distance_m). Rows not ok (exit 1), and rows whose margin is\n"
    "unknown (a group fitted with no degree of freedom left), get empty cells. A reading nearer\n"
    "than 0.4 m or at 80 deg off axis or beyond is refused. Options (default):\n"
    "  --weights FILE   weights YAML of fit_bias (required)\n"
    "  --in FILE        panel-metrics CSV (required)\n"
    "  --out FILE       corrected CSV (required)\n"
    "  --k K            standard deviations of the margin, >= 0 (2)\n";

int Fail(const std::string& what) {
  std::cerr << "correct_depth: " << what << "\n";
  return depthbias::apps::kExitError;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace depthbias;
  io::InstallSignalCleanup();
  std::string weights_path, in, out;
  double k = 2.0;
  try {
    for (apps::Args args(argc, argv); args.Next();) {
      const std::string& a = args.flag();
      if (args.IsHelp()) return apps::PrintHelp(kUsage);
      if (a == "--weights") weights_path = args.Value();
      else if (a == "--in") in = args.Value();
      else if (a == "--out") out = args.Value();
      // k standard deviations below the corrected distance: finite and >= 0, or the margin
      // would not be a distance the target is not nearer than.
      else if (a == "--k") k = args.Number(false, 0);
      else throw std::invalid_argument("unknown argument '" + a + "'");
    }
    if (weights_path.empty() || in.empty() || out.empty())
      throw std::invalid_argument("--weights, --in and --out are required");
  } catch (const std::invalid_argument& e) {
    return Fail(std::string(e.what()) + " (see correct_depth --help)");
  }
  std::vector<records::PanelMetrics> rows;
  records::BiasWeights weights;
  std::unique_ptr<model::BiasModel> bias_model;
  try {
    io::CheckOutputs({out}, {in, weights_path});
    io::CheckOutputFile(out);
    weights = io::ReadWeightsYaml(weights_path);
    rows = io::ReadMetricsCsv(in);
  } catch (const io::IoError& e) {
    return Fail(e.what());
  } catch (const std::bad_alloc&) {
    return Fail(in + ", " + weights_path + ": out of memory while reading them");
  }
  try {
    bias_model = std::make_unique<model::BiasModel>(weights);
  } catch (const std::exception& e) {
    return Fail(weights_path + ": " + e.what());
  }
  // A reading without physical meaning is refused before anything is computed (model/domain.h).
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (!rows[i].ok()) continue;
    const std::string why = model::OutsideDomain(rows[i].median_m, rows[i].angle_deg);
    if (!why.empty())
      return Fail(in + ": row " + std::to_string(i + 1) + " ('" + rows[i].bag + "'): " + why);
  }
  std::vector<std::string> header = io::MetricsColumns();
  for (const char* c : {"predicted_bias_m", "corrected_m", "predictive_std_m", "margin_m",
                        "residual_m"})
    header.push_back(c);
  std::vector<std::vector<std::string>> cells;
  std::map<std::string, std::size_t> by_status;
  for (const auto& r : rows) {
    std::vector<std::string> c = io::MetricsCells(r);
    ++by_status[r.ok() ? "ok" : "not ok"];
    if (!r.ok()) {
      c.insert(c.end(), 5, "");
      cells.push_back(std::move(c));
      continue;
    }
    try {
      const auto& s = bias_model->Scenario(r.light, r.preset, r.emitter);
      const double corrected = s.CorrectedM(r.median_m, r.angle_deg);
      c.push_back(io::CsvNumber(s.BiasM(r.median_m, r.angle_deg)));
      c.push_back(io::CsvNumber(corrected));
      c.push_back(io::CsvNumber(s.PredictiveStdM(r.median_m, r.angle_deg)));
      c.push_back(io::CsvNumber(s.SafeDistanceM(r.median_m, r.angle_deg, k)));
      c.push_back(io::CsvNumber(corrected - r.distance_m));
    } catch (const std::out_of_range& e) {
      return Fail(in + ": row '" + r.bag + "': " + e.what());
    }
    cells.push_back(std::move(c));
  }
  try {
    io::WriteCsv(out, header, cells);
  } catch (const io::IoError& e) {
    return Fail(e.what());
  }
  std::cout << "correct_depth: "
            << apps::Summary(rows.size(), "row", by_status, out) << "\n";
  // Rows that failed upstream are written with empty cells: outputs written, some rows failed.
  return by_status.count("not ok") > 0 ? apps::kExitRowsFailed : apps::kExitOk;
}
