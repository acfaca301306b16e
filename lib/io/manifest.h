#pragma once
// The manifest CSV: ground truth a bag cannot know. Columns bag, distance_m, angle_deg, light
// (required), preset, emitter (optional: otherwise read from the bag's recorded options), and
// any other columns kept by name as extras (e.g. the simulator's true_depth_m).

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "io/io_error.h"

namespace depthbias::io {

struct ManifestRow {
  std::string bag;                     // as written in the manifest (a file name or a path)
  double distance_m = 0.0;             // nominal distance of the test point
  double angle_deg = 0.0;              // nominal off-axis position
  std::string light;                   // "daylight", "sunset", ...
  std::optional<std::string> preset;   // "HA", "HD", ... if the manifest says
  std::optional<std::string> emitter;  // "on" / "off" if the manifest says
  std::map<std::string, std::string> extras;  // other columns, by name (cell text)
  int line = 0;                        // line in the manifest file
};

class Manifest {
 public:
  Manifest() = default;
  Manifest(std::string file, std::vector<ManifestRow> rows,
           std::vector<std::string> extra_columns);

  // Row for a recording, matched by path: a row's `bag` is a path relative to the manifest's
  // own folder (or absolute), `bag_path` a path as the user gave it (relative to the working
  // folder); both name the same file once made absolute and normalized (links resolved where
  // they exist). A file of the same name elsewhere (/etc/a.bag for a row `a.bag`) is not
  // matched. nullptr if none.
  const ManifestRow* Find(const std::string& bag_path) const;
  // The file a row names: its `bag` resolved against the manifest's folder.
  std::string PathOf(const ManifestRow& row) const;
  const std::vector<ManifestRow>& rows() const { return rows_; }
  const std::vector<std::string>& extra_columns() const { return extra_columns_; }
  const std::string& file() const { return file_; }

 private:
  std::string file_;
  std::vector<ManifestRow> rows_;
  std::vector<std::string> extra_columns_;  // in file order
  std::map<std::string, size_t> by_path_;  // resolved path → row
};

// Throws IoError naming file and line on a missing column, a bad number (distance_m must be
// > 0, angle_deg a number), an empty bag or light, or two rows for the same recording (the
// same path once resolved against the manifest's folder).
Manifest ParseManifest(const std::string& text, const std::string& file);
Manifest ReadManifest(const std::string& path);

// Columns bag,distance_m,angle_deg,light,preset,emitter then the extras named; written
// atomically.
std::string FormatManifest(const std::vector<ManifestRow>& rows,
                           const std::vector<std::string>& extra_columns = {});
void WriteManifest(const std::string& path, const std::vector<ManifestRow>& rows,
                   const std::vector<std::string>& extra_columns = {});

}  // namespace depthbias::io
