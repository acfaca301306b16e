// libFuzzer target: any text as a stage config (key: value YAML) and as a boxes JSON. Each
// reader either returns or throws IoError (bounded: io/yaml_limits.h), never anything else.
#include <cstdint>
#include <string>

#include "io/config_file.h"
#include "io/io_error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    (void)depthbias::io::ParseConfigScalars(text, "fuzz.yaml");
  } catch (const depthbias::io::IoError&) {
  }
  try {
    for (const auto& [name, b] : depthbias::io::ParseBoxes(text, "fuzz.json"))
      if (!(b[2] > b[0] && b[3] > b[1])) __builtin_trap();
  } catch (const depthbias::io::IoError&) {
  }
  return 0;
}
