"""Merges a unit's panel-metrics shards (one panel_extract row each) into the unit's table.

Run by workflow/Snakefile's merge_metrics rule (snakemake.input: the shards in recording-name
order, snakemake.output[0]: the table). Every shard must have the same header and one row; rows
are copied as panel_extract wrote them, so the table is the one panel_extract writes for the
whole unit folder in one run. Written to a temporary file and renamed.
"""
import csv
import io
import os
import sys


def read_shard(path):
    with open(path, newline="", encoding="utf-8") as f:
        text = f.read()
    rows = list(csv.reader(io.StringIO(text)))
    if len(rows) != 2:
        sys.exit(f"merge_metrics: {path}: expected a header and one row, found {len(rows)} rows")
    header, _, body = text.partition("\n")
    return header, body if body.endswith("\n") else body + "\n"


def main(shards, out):
    if not shards:
        sys.exit(f"merge_metrics: no shard for {out}")
    header = None
    bodies = []
    for path in shards:
        shard_header, body = read_shard(path)
        if header is None:
            header = shard_header
        elif shard_header != header:
            sys.exit(f"merge_metrics: {path}: header differs from {shards[0]}'s")
        bodies.append(body)
    tmp = out + ".part"
    with open(tmp, "w", encoding="utf-8", newline="") as f:
        f.write(header + "\n")
        f.writelines(bodies)
    os.replace(tmp, out)


if __name__ == "__main__" and "snakemake" not in globals():
    main(sys.argv[2:], sys.argv[1])  # merge_metrics.py OUT SHARD...
else:
    main(list(snakemake.input), snakemake.output[0])  # noqa: F821 (set by Snakemake)
