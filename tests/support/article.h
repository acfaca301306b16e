#pragma once
// The simulator as the article's protocol and its sensor configure it (config/protocol_paper.yaml
// and the sensor file it names), read from the source tree.

#include <stdexcept>
#include <string>

#include "io/atomic_file.h"
#include "sim/config_yaml.h"

namespace depthbias::test_support {

// Throws std::runtime_error naming what is wrong when a file does not parse.
inline sim::SimParams ArticleSimParams() {
  sim::SimParams p;
  std::string why, sensor;
  const std::string dir = DEPTHBIAS_SOURCE_DIR "/config/";
  if (!sim::ParseProtocolYaml(io::ReadFile(dir + "protocol_paper.yaml"), &p.protocol, &sensor,
                              &why) ||
      !sim::ParseSensorYaml(io::ReadFile(dir + sensor), &p.sensor, &why))
    throw std::runtime_error("fixture: " + why);
  return p;
}

}  // namespace depthbias::test_support
