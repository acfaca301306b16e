// libFuzzer target: any text as the simulator's protocol, sensor and effects YAML, as simulate
// reads them: io's limits first (io::CheckYamlText), then lib/sim's parsers, which either accept
// or say why. Nothing else may come out of them.
#include <cstdint>
#include <string>

#include "io/io_error.h"
#include "io/yaml_limits.h"
#include "sim/config_yaml.h"
#include "sim/effects.h"
#include "sim/stereo_sim.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    depthbias::io::CheckYamlText(text, "fuzz.yaml");
  } catch (const depthbias::io::IoError&) {
    return 0;
  }
  using namespace depthbias::sim;
  std::string why, sensor_file;
  SimParams params;
  if (ParseProtocolYaml(text, &params.protocol, &sensor_file, &why)) (void)params.IsValid(&why);
  SensorParams sensor;
  if (ParseSensorYaml(text, &sensor, &why)) (void)sensor.IsValid(&why);
  std::vector<EffectSpec> effects;
  Departures departures;
  if (ParseEffectsYaml(text, &effects, &why)) (void)BuildDepartures(effects, &departures, &why);
  return 0;
}
