// libFuzzer target: any text as a manifest CSV. Parsing either succeeds or throws IoError; a
// manifest that parses is written back and reads back the same.
#include <cstdint>
#include <string>

#include "io/io_error.h"
#include "io/manifest.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const depthbias::io::Manifest m = depthbias::io::ParseManifest(text, "fuzz.csv");
    for (const auto& r : m.rows())
      if (!(r.distance_m > 0 && r.distance_m <= 1000) || !(r.angle_deg > -90 && r.angle_deg < 90))
        __builtin_trap();
    const depthbias::io::Manifest back = depthbias::io::ParseManifest(
        depthbias::io::FormatManifest(m.rows(), m.extra_columns()), "round-trip.csv");
    if (back.rows().size() != m.rows().size()) __builtin_trap();
    for (std::size_t i = 0; i < m.rows().size(); ++i) {
      const auto& a = m.rows()[i];
      const auto& b = back.rows()[i];
      if (a.bag != b.bag || a.distance_m != b.distance_m || a.angle_deg != b.angle_deg ||
          a.light != b.light || a.preset != b.preset || a.emitter != b.emitter ||
          a.extras != b.extras)
        __builtin_trap();
    }
  } catch (const depthbias::io::IoError&) {
  }
  return 0;
}
