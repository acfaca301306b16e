// fit_bias: panel-metrics CSV → bias model weights YAML (DESIGN.md), and a table on stdout.
//   fit_bias --in metrics.csv --out weights.yaml [--model disp_knots|disp_tan|disp_scale|paper6]
//            [--lambda 0.001] [--loss auto|none|huber|cauchy|soft_l1] [--loss-scale 1.0]
//            [--group-by light,preset] [--cv point,distance|point|distance|none]
//            [--weight-valid] [--focal-px 640] [--baseline-m 0.095] [--prior name=mean:strength]
#include <cstdio>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "io/atomic_file.h"
#include "io/metrics_csv.h"
#include "io/sha256.h"
#include "io/weights_yaml.h"
#include "model/fit_groups.h"

namespace {

using namespace depthbias;

std::vector<std::string> Split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  for (std::string item; std::getline(ss, item, ',');) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

int Fail(const std::string& what) {
  std::cerr << "fit_bias: " << what << "\n";
  return 1;
}

double ToDouble(const std::string& flag, const std::string& text) {
  size_t used = 0;
  const double v = std::stod(text, &used);
  if (used != text.size()) throw std::invalid_argument(flag + " '" + text + "' is not a number");
  return v;
}

}  // namespace

int main(int argc, char** argv) {
  std::string in, out;
  model::FitGroupsParams params;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      auto value = [&]() -> std::string {
        if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
        return argv[++i];
      };
      if (a == "--in") in = value();
      else if (a == "--out") out = value();
      else if (a == "--model") params.fit.model = value();
      else if (a == "--lambda") params.fit.lambda = ToDouble(a, value());
      else if (a == "--loss-scale") params.fit.loss_scale_m = ToDouble(a, value());
      else if (a == "--focal-px") params.fit.focal_px = ToDouble(a, value());
      else if (a == "--baseline-m") params.fit.baseline_m = ToDouble(a, value());
      else if (a == "--weight-valid") params.fit.weight_by_valid_pixels = true;
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
        if (eq == std::string::npos || colon == std::string::npos || colon < eq) {
          throw std::invalid_argument("--prior expects name=mean:strength, got '" + v + "'");
        }
        params.fit.priors.push_back({v.substr(0, eq),
                                     ToDouble("--prior", v.substr(eq + 1, colon - eq - 1)),
                                     ToDouble("--prior", v.substr(colon + 1))});
      } else {
        throw std::invalid_argument("unknown argument '" + a + "'");
      }
    }
  } catch (const std::exception& e) {
    return Fail(std::string("bad arguments: ") + e.what());
  }
  if (in.empty() || out.empty()) return Fail("usage: fit_bias --in metrics.csv --out w.yaml");
  std::string why;
  if (!params.IsValid(&why)) return Fail(why);

  std::vector<camera::PanelMetrics> rows;
  std::string sha;
  try {
    rows = io::ReadMetricsCsv(in);
    sha = io::Sha256File(in);
  } catch (const io::IoError& e) {
    return Fail(e.what());
  }
  const model::FitReport report = model::FitGroups(rows, params);
  if (!report.success) return Fail(in + ": " + report.message);

  camera::BiasWeights weights = model::ToWeights(report, params);
  weights.input_file = in;
  weights.input_sha256 = sha;
  weights.tool = "fit_bias";
  weights.tool_version = DEPTHBIAS_VERSION;
  try {
    io::WriteWeightsYaml(out, weights);
  } catch (const io::IoError& e) {
    return Fail(e.what());
  }

  std::printf("model %s  loss %s (scale %g m)  lambda %g  rows %d used, %d skipped  %.3f s\n",
              weights.model.c_str(), weights.loss.c_str(), weights.loss_scale_m, weights.lambda,
              report.rows_used, report.rows_skipped, report.seconds);
  std::printf("%-10s %-7s %3s %8s %8s", "light", "preset", "n", "rmse_m", "mae_m");
  for (auto s : params.cv) {
    if (s == model::CvScheme::kNone) continue;
    const std::string n = model::CvSchemeName(s);
    std::printf(" %14s %13s", ("cv_" + n + "_rmse").c_str(), ("cv_" + n + "_mae").c_str());
  }
  std::printf("  weights\n");
  for (const auto& g : report.groups) {
    std::printf("%-10s %-7s %3d %8.3f %8.3f", g.group.light.c_str(), g.group.preset.c_str(),
                g.fit.n, g.fit.rmse_m, g.fit.mae_m);
    for (const auto& cv : g.cv) std::printf(" %14.3f %13.3f", cv.rmse_m, cv.mae_m);
    std::printf(" ");
    for (size_t j = 0; j < g.fit.names.size(); ++j) {
      std::printf(" %s=%.3f", g.fit.names[j].c_str(), g.fit.values[j]);
    }
    std::printf("\n");
  }
  return 0;
}
