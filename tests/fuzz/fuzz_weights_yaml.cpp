// libFuzzer target: any text as a weights YAML. Reading either succeeds or throws IoError; what
// it reads either builds a bias model or is refused with std::invalid_argument; a model built
// gives, at plausible depths and angles, a finite bias or NaN and a standard deviation that is
// NaN or >= 0 (never a negative margin term). What reads writes back and reads the same (a
// group's disparity noise too: a positive σ_d of at least one recording, or none).
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "io/io_error.h"
#include "io/weights_yaml.h"
#include "model/bias_model.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  depthbias::records::BiasWeights w;
  try {
    w = depthbias::io::ParseWeightsYaml(text, "fuzz.yaml");
  } catch (const depthbias::io::IoError&) {
    return 0;
  }
  const auto back =
      depthbias::io::ParseWeightsYaml(depthbias::io::FormatWeightsYaml(w), "round-trip.yaml");
  if (back.groups.size() != w.groups.size() || back.model != w.model) __builtin_trap();
  for (std::size_t i = 0; i < w.groups.size(); ++i) {
    const auto& a = w.groups[i].disparity_noise;
    const auto& b = back.groups[i].disparity_noise;
    if (a.known != b.known || (a.known && (!(a.sigma_px > 0) || a.sigma_px != b.sigma_px ||
                                           a.recordings < 1 || a.recordings != b.recordings)))
      __builtin_trap();
  }
  try {
    const depthbias::model::BiasModel model(w);
    for (const auto& g : w.groups) {
      const auto& s = model.Scenario(g.light, g.preset, g.emitter);
      for (double z : {0.5, 4.0, 16.0})
        for (double a : {-35.0, 0.0, 20.0}) {
          const double sd = s.PredictiveStdM(z, a);
          if (sd < 0) __builtin_trap();
          (void)s.SafeDistanceM(z, a, 2.0);
        }
    }
  } catch (const std::invalid_argument&) {
  } catch (const std::out_of_range&) {
  }
  return 0;
}
