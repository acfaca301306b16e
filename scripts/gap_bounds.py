#!/usr/bin/env python3
"""The best any diagnosis could do on the withheld suite's range-law cases.

A range law (a disparity offset, a depth scale) moves the median depth of every recording; the
placement of a test point (light, distance, angle) moves its four recordings' medians together
by a normal draw of placement_pct % of its distance (lib/gap/cases.h). With the placement's
scatter and the replicate noise known, and the median read at every test point, the Fisher
information of the law's size gives the smallest standard error an unbiased estimator can have
(Cramér–Rao). From it:

- power: the chance a two-sided 5 % test of the size finds the law (|estimate| > 1.96 se);
- within 20 %: the chance the estimate lies within 20 % of the injected size (the suite's size
  criterion, lib/gap/cases_judge.cpp; for a law in one light, the other light's value must lie
  within 20 % of the injected size of 0 too);
- both: the chance of both at once, and the passes that gives over five seeds at best.

An unbiased, efficient estimator that uses the median alone reaches these figures; no unbiased
one does better on these tables, whatever else it reads, unless another metric carries
information on the size that the placement does not also move (a biased one, shrunk towards a
guess, can do better where the guess is right). The
calibration, the placement's own estimate, the outer folds and the other candidates only take
information away. Pairs are read jointly (Monte Carlo over the estimate's normal law, seeded).

With --tables DIR..., each DIR a `diagnose_gap --cases --out DIR` folder (one per seed), each
case's own table is read the same way: its test points' median departures from the base
simulation (gap.json's cells, real − sim, averaged over a test point's recordings) regressed on the
laws' secants under the placement's law. Whether that table's medians themselves put every size
within 20 %, seed by seed, beside whether the case passed (DIR/cases.md), tells a failure the
table's draw made (the medians miss too) from one the diagnosis made (they hold). Beside a
temporal drift, whose size the temporal spread gives, its median shift is known and taken off:
an offset of rate × the mean frame time (the diagnosis's 10 frames at 30 fps: 0.15 s). The
sizes read against are each folder's own, from its cases.md's injected column (the suite's one
definition, lib/gap/cases.cpp), not the list above.

Usage: .venv/bin/python scripts/gap_bounds.py [--protocol config/protocol_paper.yaml]
       [--sensor config/sensor_calibrated.yaml] [--placement-pct 2] [--tables DIR...]
"""

import argparse
import json
import math
import os
import sys

import numpy as np
import yaml


def phi(x):
    return 0.5 * (1 + math.erf(x / math.sqrt(2)))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--protocol", default="config/protocol_paper.yaml")
    ap.add_argument("--sensor", default="config/sensor_calibrated.yaml")
    ap.add_argument("--placement-pct", type=float, default=2.0)
    ap.add_argument("--median-noise-at-10m", type=float, default=0.0043,
                    help="replicate noise of one recording's median at 10 m, m (∝ D²; the "
                         "suite's null tables read 0.0043)")
    ap.add_argument("--recordings", type=int, default=4,
                    help="recordings sharing a test point's placement (presets × emitter)")
    ap.add_argument("--tables", nargs="+", default=[], metavar="DIR",
                    help="diagnose_gap --cases output folders, one per seed: each case's own "
                         "table read on its medians")
    args = ap.parse_args()
    if not (args.placement_pct > 0) or not (args.median_noise_at_10m >= 0) or args.recordings < 1:
        sys.exit("gap_bounds: --placement-pct must be > 0, --median-noise-at-10m >= 0 and "
                 "--recordings >= 1")

    def read(path, what):
        try:
            with open(path) as f:
                doc = yaml.safe_load(f)
        except (OSError, UnicodeDecodeError, yaml.YAMLError) as e:
            sys.exit(f"gap_bounds: {path}: cannot read it as YAML ({e.__class__.__name__})")
        out = doc.get(what, doc) if isinstance(doc, dict) else doc
        if not isinstance(out, dict):
            sys.exit(f"gap_bounds: {path}: no '{what}' mapping")
        return out

    p = read(args.protocol, "protocol")
    s = read(args.sensor, "sensor")
    try:
        distances = [float(d) for d in p["distances_m"]]
        angles = [float(a) for a in p["angles_deg"]]
        lights = [str(x) for x in p.get("lights", ["daylight", "sunset"])]
        fb = float(s["fx"]) * float(s["baseline_m"])
    except (KeyError, TypeError, ValueError) as e:
        sys.exit(f"gap_bounds: {args.protocol}, {args.sensor}: a key missing or not a number "
                 f"({e})")
    if (not distances or not angles or not lights or not (fb > 0) or min(distances) <= 0
            or max(abs(a) for a in angles) >= 90):
        sys.exit(f"gap_bounds: {args.protocol}, {args.sensor}: no distances, angles or lights, "
                 "a distance <= 0, an angle of 90° or more, or f·B <= 0")
    if not all(isinstance(x, (str, int, float)) for x in p.get("lights", [])):
        sys.exit(f"gap_bounds: {args.protocol}: lights must be names")
    # The panel centre's depth: a range protocol's distance is along the line of sight.
    along_sight = p.get("distance_is", "range") == "range"
    points = [(light, d * (math.cos(math.radians(a)) if along_sight else 1), a)
              for light in lights for d in distances for a in angles]

    def sd_point(z):  # one test point's mean median: placement (along the sight line) and noise
        tau = args.placement_pct / 100 * z
        sigma = args.median_noise_at_10m * (z / 10) ** 2 / math.sqrt(args.recordings)
        return math.hypot(tau, sigma)

    def slope(law, value, z):  # d(median depth)/d(size) at the injected size, depth z
        if law == "disparity_offset":
            zp = fb / (fb / z + value)
            return -zp * zp / fb
        if law == "depth_scale":
            return z
        raise ValueError(law)

    def info(laws, light_only=None):
        """Fisher information matrix of the laws' sizes (laws: [(name, value)])."""
        m = np.zeros((len(laws), len(laws)))
        for light, z, _ in points:
            if light_only is not None and light != light_only:
                continue
            g = np.array([slope(n, v, z) for n, v in laws])
            m += np.outer(g, g) / sd_point(z) ** 2
        return m

    print(f"f·B = {fb:.1f} px·m; {len(points)} test points ({len(lights)} lights × "
          f"{len(distances)} distances × {len(angles)} angles), {args.recordings} recordings "
          f"each; placement {args.placement_pct:g} % of distance, replicate noise of the median "
          f"{args.median_noise_at_10m:g} m at 10 m")
    print()
    print("| case | law | injected | smallest se | injected / se | power (5 %) | within 20 % "
          "| both | passes in 5 seeds at best |")
    print("|---|---|---|---|---|---|---|---|---|")
    cases = [
        ("disparity_offset small", [("disparity_offset", 0.07)], None),
        ("disparity_offset at the noise floor", [("disparity_offset", 0.06)], None),
        ("disparity_offset large", [("disparity_offset", 0.35)], None),
        ("depth_scale small", [("depth_scale", 0.01)], None),
        ("depth_scale large", [("depth_scale", 0.06)], None),
        # Fitted per light, the sunset value from the sunset test points alone.
        ("disparity_offset sunset only", [("disparity_offset", 0.15)], "sunset"),
        ("disparity_offset + depth_scale", [("disparity_offset", 0.15), ("depth_scale", 0.02)],
         None),
    ]
    rng = np.random.default_rng(1)
    for name, laws, light in cases:
        if light and light not in lights:
            continue
        try:
            cov = np.linalg.inv(info(laws, light))
            # A law in one light: each other light's value, 0, read within 20 % of the size.
            others = [np.linalg.inv(info([(n, 0.0) for n, _ in laws], o))[0, 0]
                      for o in lights if light and o != light]
        except np.linalg.LinAlgError:
            sys.exit(f"gap_bounds: {args.protocol}: the test points do not determine {name}")
        se = np.sqrt(np.diag(cov))
        truth = np.array([v for _, v in laws])
        others_within = 1.0
        for var in others:
            others_within *= 2 * phi(0.2 * abs(truth[0]) / math.sqrt(var)) - 1
        if len(laws) == 1:  # exact: the estimate within 20 % of a positive size, and beyond 1.96 se
            t, s0 = abs(truth[0]), se[0]
            both = max(0.0, phi((1.2 * t - t) / s0) - phi((max(0.8 * t, 1.96 * s0) - t) / s0))
        else:  # jointly, by draws
            draws = rng.multivariate_normal(truth, cov, size=200000)
            found = np.all(np.abs(draws) > 1.96 * se, axis=1)
            within = np.all(np.abs(draws - truth) < 0.2 * np.abs(truth), axis=1)
            both = float(np.mean(found & within))
        both *= others_within
        for i, (law, value) in enumerate(laws):
            z = abs(value) / se[i]
            power = phi(z - 1.96) + phi(-z - 1.96)
            w20 = (2 * phi(0.2 * abs(value) / se[i]) - 1) * others_within
            last = i == len(laws) - 1
            print(f"| {name if i == 0 else ''} | {law} | {value:g} | {se[i]:.3g} | {z:.2f} | "
                  f"{power:.2f} | {w20:.2f} | {f'{both:.2f}' if last else ''} | "
                  f"{f'{5 * both:.1f}' if last else ''} |")
        if len(laws) == 2:
            r = cov[0, 1] / (se[0] * se[1])
            print(f"|  | (the pair's estimates correlate r = {r:.3f}) | | | | | | | |")
    if args.tables:
        try:
            fps = float(p.get("fps", 30))
        except (TypeError, ValueError):
            sys.exit(f"gap_bounds: {args.protocol}: fps is not a number")
        if not fps > 0:
            sys.exit(f"gap_bounds: {args.protocol}: fps must be > 0")
        # The offset beside a drift, whose median shift is known (its size from cases.md).
        names = [name for name, _, _ in cases] + ["disparity_offset + temporal_drift"]
        print()
        print(tables_report(args.tables, names, fb, along_sight, sd_point, fps))


def case_file(name):
    """A case's gap.json in DIR/cases: each byte of its name not a letter or digit an underscore
    (apps/diagnose_gap.cpp)."""
    return "".join(chr(b) if chr(b).isascii() and chr(b).isalnum() else "_"
                   for b in name.encode("utf-8")) + ".json"


RANGE_LAWS = {"disparity_offset": "delta_px", "depth_scale": "scale_rel"}


def parse_injected(text):
    """cases.md's injected column -> (range laws [(name, size)], drift rate px/s, light or None),
    or None where it names anything else: "disparity_offset (delta_px 0.15, sunset only);
    temporal_drift (rate_px_per_s 0.6)"."""
    laws, drift, light = [], 0.0, None
    for part in text.split(";"):
        part = part.strip()
        if "(" not in part or not part.endswith(")"):
            return None
        name, inside = part[:-1].split("(", 1)
        name, values = name.strip(), {}
        for item in inside.split(","):
            words = item.split()
            if not words:
                return None
            if len(words) == 2 and words[1] == "only":
                light = words[0]
                continue
            try:
                values[words[0]] = float(words[1]) if len(words) == 2 else None
            except ValueError:
                return None
        if name == "temporal_drift" and values.get("rate_px_per_s") is not None:
            drift = values["rate_px_per_s"]
        elif name in RANGE_LAWS and values.get(RANGE_LAWS[name]) is not None:
            laws.append((name, values[RANGE_LAWS[name]]))
        else:
            return None
    return (laws, drift, light) if laws else None


def read_cases_md(folder):
    """Case name -> (passed, injected text), from DIR/cases.md's table."""
    out = {}
    try:
        with open(os.path.join(folder, "cases.md"), encoding="utf-8") as f:
            for line in f:
                cells = [c.strip() for c in line.split("|")]
                if len(cells) > 9 and cells[1] not in ("case", "---"):
                    out[cells[1]] = (cells[8] == "yes", cells[2])
    except OSError as e:
        sys.exit(f"gap_bounds: {folder}/cases.md: cannot read it ({e.strerror})")
    return out


def tables_report(folders, names, fb, along_sight, sd_point, fps):
    """Each named case's table read on its own medians, seed by seed (module docstring), against
    the sizes its folder's cases.md says were injected. A drift's median shift is an offset of
    its rate times the mean frame time, (frames − 1) / 2 / fps, the frames those of the case's
    diagnosis (gap.json's settings)."""
    def secant(law, value, z):  # the law's whole move of the median over its size
        if law == "disparity_offset":
            return (fb / (fb / z + value) - z) / value if value else -z * z / fb
        return z

    lines = ["| case | the table's medians put every size within 20 % | the case passes | "
             "seed by seed: the medians' sizes (within 20 %?; passed?) |", "|---|---|---|---|"]
    rows_of = {folder: read_cases_md(folder) for folder in folders}
    for name in names:
        shown, held, passed, seen = [], 0, 0, 0
        for folder in folders:
            path = os.path.join(folder, "cases", case_file(name))
            if not os.path.exists(path):
                continue
            if name not in rows_of[folder]:
                sys.exit(f"gap_bounds: {folder}/cases.md: no row for \"{name}\", whose "
                         "gap.json is there")
            did, injected = rows_of[folder][name]
            parsed = parse_injected(injected)
            if parsed is None:
                sys.exit(f"gap_bounds: {folder}/cases.md: \"{name}\": cannot read the range "
                         f"laws' sizes in its injected column (\"{injected}\")")
            laws, drift, light = parsed
            try:
                with open(path, encoding="utf-8") as f:
                    doc = json.load(f)
                cells = doc["cells"]
                frames = int(doc["settings"]["frames"])
            except (OSError, ValueError, KeyError, TypeError) as e:
                sys.exit(f"gap_bounds: {path}: cannot read its cells and frames ({e})")
            points = {}
            try:
                for c in cells:
                    real, sim = c["real"].get("median_bias_m"), c["sim"].get("median_bias_m")
                    if light and c["light"] != light:
                        continue
                    if isinstance(real, (int, float)) and isinstance(sim, (int, float)):
                        points.setdefault((c["light"], float(c["distance_m"]),
                                           float(c["angle_deg"])), []).append(real - sim)
            except (KeyError, TypeError, AttributeError, ValueError) as e:
                sys.exit(f"gap_bounds: {path}: a cell without its light, distance, angle, "
                         f"real or sim ({e.__class__.__name__}: {e})")
            if len(points) < len(laws):
                sys.exit(f"gap_bounds: {path}: {len(points)} test points with a median, too few "
                         "to read the case's laws")
            shift = drift * (frames - 1) / 2 / fps
            total = shift + sum(v for n, v in laws if n == "disparity_offset")
            x, y, w = [], [], []
            for (_, d, a), dep in sorted(points.items()):
                z = d * (math.cos(math.radians(a)) if along_sight else 1)
                x.append([secant(n, total if n == "disparity_offset" else v, z)
                          for n, v in laws])
                y.append(np.mean(dep) - shift * secant("disparity_offset", total, z))
                w.append(1 / sd_point(z) ** 2)
            x, y, w = np.array(x), np.array(y), np.array(w)
            fitted = np.linalg.lstsq(x * np.sqrt(w)[:, None], y * np.sqrt(w), rcond=None)[0]
            ok = all(abs(f - v) <= 0.2 * abs(v) for f, (_, v) in zip(fitted, laws))
            seen += 1
            held += ok
            passed += bool(did)
            shown.append(f"{os.path.basename(os.path.normpath(folder))}: "
                         + ", ".join(f"{f:.3g}" for f in fitted)
                         + f" ({'holds' if ok else 'misses'}; "
                         + f"{'passed' if did else 'failed'})")
        if seen:
            lines.append(f"| {name} | {held} of {seen} | {passed} of {seen} | "
                         + "; ".join(shown) + " |")
    return "\n".join(lines)


if __name__ == "__main__":
    main()
