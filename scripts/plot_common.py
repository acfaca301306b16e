"""Shared pieces of the plot scripts (scripts/plot_*.py): reading depthbias's CSV and YAML
outputs, the scenario order, evaluating a fitted model on a grid with the real correct_depth,
and writing a PNG of a fixed size (written to a temporary file, then renamed).

Every figure has a fixed size in pixels (FIG_DPI x its figsize in inches): the tests check it
by reading the PNG header (scripts/plot_check.py).
"""
import csv
import math
import os
import subprocess
import sys
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

FIG_DPI = 100
HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, ".."))
DEFAULT_BIN = os.path.join(ROOT, "build", "apps")
UMASK = os.umask(0)
os.umask(UMASK)

# The article's 12 columns, the metrics CSV's first ones (DESIGN.md "Panel metrics CSV").
ARTICLE_COLUMNS = ["bag", "light", "emitter", "preset", "distance_m", "angle_deg", "frames",
                   "mean_m", "median_m", "plane_std_m", "hole_rate_pct", "valid_pct"]
LIGHT_ORDER = {"daylight": 0, "sunset": 1}
PRESET_ORDER = {"HA": 0, "HD": 1}
PRESET_NAMES = {"HA": "High Accuracy", "HD": "High Density"}

plt.rcParams.update({
    "font.size": 11, "axes.titlesize": 12, "axes.labelsize": 11, "legend.fontsize": 9,
    "xtick.labelsize": 10, "ytick.labelsize": 10, "figure.titlesize": 14,
})


class InputError(Exception):
    """Input the script cannot use: reported on one line naming the file."""


def fail(script, message):
    print(f"{os.path.basename(script)}: {message}", file=sys.stderr)
    sys.exit(2)


def run_main(script, main):
    """Runs main(); bad input ends with a one-line error and exit status 2."""
    try:
        main()
    except InputError as e:
        fail(script, str(e))


def read_csv(path, required=()):
    """Rows of a CSV as dicts; refuses a missing file or missing columns in one line."""
    if not os.path.isfile(path):
        raise InputError(f"{path}: no such file")
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        if reader.fieldnames is None:
            raise InputError(f"{path}: empty file, expected a CSV header")
        missing = [c for c in required if c not in reader.fieldnames]
        if missing:
            raise InputError(f"{path}: missing column(s) {', '.join(missing)}")
        rows = list(reader)
    if not rows:
        raise InputError(f"{path}: no data rows")
    return rows


def number(row, key, path="", default=None):
    """A float from a CSV cell; empty gives default (None: an error naming the file)."""
    text = row.get(key, "")
    if text is None or text.strip() == "":
        if default is not None:
            return default
        raise InputError(f"{path}: row '{row.get('bag', '?')}' has no value for {key}")
    try:
        return float(text)
    except ValueError:
        raise InputError(f"{path}: row '{row.get('bag', '?')}': {key} = '{text}' is not a number")


def ok_rows(rows):
    """Rows whose status is ok (the article's rows have no status column: all kept)."""
    return [r for r in rows if r.get("status", "ok") in ("", "ok")]


def scenario_key(light, preset):
    return (LIGHT_ORDER.get(light, 9), light, PRESET_ORDER.get(preset, 9), preset)


def scenarios(rows):
    """The (light, preset) pairs of a table, daylight before sunset, HA before HD."""
    pairs = {(r["light"], r["preset"]) for r in rows}
    return sorted(pairs, key=lambda p: scenario_key(*p))


def scenario_title(light, preset):
    return f"{light}, {PRESET_NAMES.get(preset, preset)} ({preset})"


def read_weights(path):
    """A weights YAML (fit_bias --out) as a dict; groups keyed by (light, preset)."""
    import yaml
    if not os.path.isfile(path):
        raise InputError(f"{path}: no such file")
    with open(path) as f:
        try:
            doc = yaml.safe_load(f)
        except yaml.YAMLError as e:
            raise InputError(f"{path}: not YAML ({str(e).splitlines()[0]})")
    if not isinstance(doc, dict) or not isinstance(doc.get("groups"), list):
        raise InputError(f"{path}: not a weights YAML (no 'groups' list)")
    doc["by_scenario"] = {(g.get("light"), g.get("preset")): g for g in doc["groups"]}
    return doc


def model_label(weights):
    names = {"paper6": "eq. 6 (article's form)", "disp_knots": "disp_knots (default)",
             "disp_tan": "disp_tan", "disp_scale": "disp_scale"}
    return names.get(weights.get("model"), str(weights.get("model")))


def tool(bin_dir, name):
    path = os.path.join(bin_dir, name)
    if not os.access(path, os.X_OK):
        raise InputError(f"{path}: not found or not executable (build first: scripts/build.sh)")
    return path


def evaluate_grid(bin_dir, weights_path, scenario_list, depths_m, angles_deg, k=2.0):
    """Evaluates a fitted model on a depth x angle grid per scenario with the real correct_depth
    (the one implementation of the models): one grid row per (measured depth Z, angle).

    Returns {(light, preset): {"bias": B, "std": S, "corrected": C, "safe": M}}, each a list of
    rows (one per angle) of columns (one per depth). A grid row's distance_m is Z / cos(angle),
    the range of a target with no bias; correct_depth does not use it.
    """
    with tempfile.TemporaryDirectory() as tmp:
        grid = os.path.join(tmp, "grid.csv")
        with open(grid, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(ARTICLE_COLUMNS)
            i = 0
            for light, preset in scenario_list:
                for a in angles_deg:
                    for z in depths_m:
                        i += 1
                        d = z / math.cos(math.radians(a))
                        w.writerow([f"grid{i}", light, "on", preset, f"{d:.6f}", f"{a:.6f}", 1,
                                    f"{z:.6f}", f"{z:.6f}", 0, 0, 100])
        columns = {"bias": "predicted_bias_m", "std": "predictive_std_m",
                   "corrected": "corrected_m", "safe": "margin_m"}
        values = correct(bin_dir, weights_path, grid, k, name=weights_path,
                         columns=list(columns.values()))
    result = {}
    n = len(depths_m)
    row = 0
    for s in scenario_list:
        maps = {key: [] for key in columns}
        for _ in angles_deg:
            for key, col in columns.items():
                maps[key].append(values[col][row:row + n])
            row += n
        result[s] = maps
    return result


def correct(bin_dir, weights_path, metrics_path, k=2.0, name=None, columns=None):
    """correct_depth on a metrics CSV: its rows with predicted_bias_m, corrected_m,
    predictive_std_m, margin_m, residual_m; with `columns`, only those, as {column: [floats]}
    (faster for large grids). Errors name `name` (default: the metrics CSV)."""
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "corrected.csv")
        cmd = [tool(bin_dir, "correct_depth"), "--weights", weights_path, "--in", metrics_path,
               "--out", out, "--k", str(k)]
        done = subprocess.run(cmd, capture_output=True, text=True)
        if done.returncode != 0:
            raise InputError(f"{name or metrics_path}: correct_depth failed: "
                             f"{(done.stderr or done.stdout).strip().splitlines()[-1]}")
        if columns is None:
            return read_csv(out)
        with open(out, newline="") as f:
            reader = csv.reader(f)
            header = next(reader)
            index = [header.index(c) for c in columns]
            values = {c: [] for c in columns}
            for line in reader:
                for c, i in zip(columns, index):
                    values[c].append(float(line[i]))
        return values


def add_grid_arguments(ap):
    """--max-angle and --grid of the figures drawn over measured depth x off-axis angle."""
    ap.add_argument("--max-angle", type=float, default=35.0)
    ap.add_argument("--grid", type=int, nargs=2, default=(161, 71), metavar=("DEPTHS", "ANGLES"),
                    help="grid points in depth and in angle (fewer: faster, coarser)")


def check_grid(args):
    if min(args.grid) < 3:
        raise InputError(f"--grid {args.grid[0]} {args.grid[1]}: at least 3 points each")


def linspace(lo, hi, n):
    return [lo + (hi - lo) * i / (n - 1) for i in range(n)]


def save(fig, path):
    """Writes the figure at FIG_DPI (no tight bounding box: the size in pixels is the figure's),
    to a temporary file beside the output, renamed at the end."""
    folder = os.path.dirname(os.path.abspath(path))
    os.makedirs(folder, exist_ok=True)
    fd, tmp = tempfile.mkstemp(suffix=".png", dir=folder)
    os.close(fd)
    try:
        fig.savefig(tmp, dpi=FIG_DPI, format="png")
        os.chmod(tmp, 0o666 & ~UMASK)  # mkstemp's 0600 would outlive the rename
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)
    plt.close(fig)
    print(f"wrote {path}")


def hull(points):
    """Convex hull (Andrew's monotone chain) of 2-D points, closed."""
    pts = sorted(set(points))
    if len(pts) < 3:
        return pts

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower, upper = [], []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    for p in reversed(pts):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return lower[:-1] + upper[:-1] + [lower[0]]
