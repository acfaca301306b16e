#pragma once
// The simulator's YAML documents, parsed from text (the app reads the files through io): the
// protocol (config/protocol_paper.yaml), the sensor (config/sensor_calibrated.yaml) and the
// effects list. A document overrides only the keys it names; an unknown key, a value of the
// wrong type or out of bounds is an error with a one-line reason naming the key.

#include <map>
#include <string>
#include <vector>

#include "sim/effects.h"
#include "sim/scene.h"
#include "sim/sensor.h"

namespace depthbias::sim {

// protocol: {distances_m, angles_deg, presets, emitters, lights, distance_is, frames, fps},
// scene: {...SceneParams, panel: on|off, obstacles: [{kind, range_m, azimuth_deg, [width_m,
// depth_m, height_m, texture]}, ...], hedge: {distance_m, height_m, texture}}, and optionally
// sensor: FILE (a sensor YAML, relative to the protocol file's folder) returned in *sensor_file.
bool ParseProtocolYaml(const std::string& text, ProtocolParams* protocol,
                       std::string* sensor_file, std::string* why);

// sensor: {width, height, fx, fy, ppx, ppy, baseline_m, depth_units_m, ..., fallback:
// {sigma_d_px, invalid_prob}, scenarios: [{light, preset, sigma_d_px, invalid_prob}, ...]}.
// A top-level calibration: block (written by the calibration) is accepted and ignored.
bool ParseSensorYaml(const std::string& text, SensorParams* sensor, std::string* why);

// effects: [{name: disparity_offset, delta_px: 0.2}, ...]. Checks every name and parameter
// against the registry (BuildDepartures gives the departures).
bool ParseEffectsYaml(const std::string& text, std::vector<EffectSpec>* effects,
                      std::string* why);

// The sensor as a YAML document that ParseSensorYaml reads back, after the comment lines given
// (each prefixed with "# "), and with extra top-level text appended (e.g. a calibration block).
std::string FormatSensorYaml(const SensorParams& sensor, const std::vector<std::string>& comments,
                             const std::string& extra_yaml = "");

// Takes what a recording says about its camera: depth intrinsics (treated as rectified: the
// D455 depth stream reports zero distortion; the model becomes none), depth units (the maximum
// depth is capped to what 16-bit counts hold at them, as on the camera), and the
// Stereo_Baseline option (millimetres, as librealsense records it) when present.
void ApplyRecording(const camera::Intrinsics& intrinsics, double depth_units_m,
                    const std::map<std::string, double>& options, SensorParams* sensor);

}  // namespace depthbias::sim
