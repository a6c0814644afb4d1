#!/usr/bin/env python3
"""Check an odocal Rerun recording with the official rerun-sdk.

Usage: rrd_check.py RECORDING.rrd EXPECT.json   (EXPECT may also be '-' for stdin)

EXPECT is a JSON object:
  {
    "version": "0.36.3",                  # optional: required rerun-sdk version
    "timelines": ["scan", "time"],        # every temporal row must carry these
                                          # (an entity may list its own "timelines")
    "exact": true,                        # no entities beyond the listed ones
    "blueprint": ["/world", ...],         # optional: view origins the stored
                                          # blueprint must have
    "entities": {
      "world/map":  {"static": true, "rows": 1},
      "world/scan": {"rows": 10, "instances": {"Points2D:positions": 5410},
                     "first": {"scan": 0, "time": 0.0}, "last": {"scan": 9, "time": 0.9}},
      ...
    }
  }
    "cursors": [                          # optional: what a latest-at viewer shows
      {"prefix": "world/icp_covariance/trail",  # every entity at or below it
       "timeline": "scan", "at": 10,            # the cursor
       "component": "LineStrips2D:strips",
       "depth": 1,                               # 1: count the rows' instances
                                                 # 2: count the points inside them
       "want": 10},
      ...
    ]
  }
A cursor sums, over the entities at or below "prefix", the instances of "component"
in each entity's latest row at or before "at" on "timeline" (the row the viewer
draws there; nothing for an entity with no row yet).
The recording's blueprint (a separate store in the file) is not counted among the
entities; its view origins are listed under "blueprint" in the summary.
"rows" counts logged rows (one per log call or per send_columns row); "instances"
sums the list lengths of a component column over all rows. "first"/"last" are
the smallest/largest values on a timeline (sequence as int, duration in s).

The file is also passed to `rerun rrd verify` (same package). Prints a JSON
summary of what was found on stdout; problems on stderr; exit 0 only if every
expectation holds.
"""

import json
import subprocess
import sys

import pyarrow as pa
import pyarrow.compute as pc
import rerun
import rerun.experimental as rrx

IGNORED_TIMELINES = {"log_time", "log_tick"}


def norm(path):
    return "/" + path.strip("/")


def timeline_value(col):
    """Numbers of a timeline column: sequence as int, duration and timestamp
    as seconds (since 1970 for a timestamp)."""
    if pa.types.is_duration(col.type) or pa.types.is_timestamp(col.type):
        unit = col.type.unit
        scale = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9}[unit]
        ints = pc.cast(col, pa.int64())
        return [None if v is None else v * scale for v in ints.to_pylist()]
    return col.to_pylist()


def row_counts(col, depth):
    """Per row: the list length (depth 1) or the summed inner lengths (depth 2)."""
    if depth == 1:
        return pc.list_value_length(col).fill_null(0).to_pylist()
    return [sum(len(inner or []) for inner in (row or [])) for row in col.to_pylist()]


def scan(path, cursors=()):
    """Per entity: static rows, temporal rows, timelines, instances, first/last;
    and, for the entities under a cursor's prefix, every temporal row's timeline
    values and counts (in "rows_of", used by check_cursors)."""
    found = {}
    wanted = [(norm(c["prefix"]), c["component"], c.get("depth", 1)) for c in cursors]
    for chunk in rrx.RrdReader(path).stream():
        ent = str(chunk.entity_path)
        if ent.startswith("/__"):
            continue
        e = found.setdefault(
            ent,
            {"static_rows": 0, "rows": 0, "timelines": None, "instances": {},
             "first": {}, "last": {}, "rows_of": []},
        )
        rb = chunk.to_record_batch()
        n = chunk.num_rows
        if chunk.is_static:
            e["static_rows"] += n
        else:
            e["rows"] += n
            tls = set(chunk.timeline_names) - IGNORED_TIMELINES
            e["timelines"] = tls if e["timelines"] is None else e["timelines"] & tls
            for tl in tls:
                vals = [v for v in timeline_value(rb.column(tl)) if v is not None]
                if vals:
                    lo, hi = min(vals), max(vals)
                    e["first"][tl] = lo if tl not in e["first"] else min(e["first"][tl], lo)
                    e["last"][tl] = hi if tl not in e["last"] else max(e["last"][tl], hi)
            for prefix, comp, depth in wanted:
                if (ent == prefix or ent.startswith(prefix + "/")) and comp in rb.schema.names:
                    counts = row_counts(rb.column(comp), depth)
                    stamps = {tl: timeline_value(rb.column(tl)) for tl in tls}
                    for i, c in enumerate(counts):
                        e["rows_of"].append(
                            ({tl: v[i] for tl, v in stamps.items()}, comp, depth, c))
        for name in rb.schema.names:
            if ":" not in name:
                continue
            col = rb.column(name)
            if pa.types.is_list(col.type) or pa.types.is_large_list(col.type):
                lengths = pc.list_value_length(col).fill_null(0)
                total = pc.sum(lengths).as_py() or 0
            else:
                total = len(col) - col.null_count
            e["instances"][name] = e["instances"].get(name, 0) + total
    for e in found.values():
        e["timelines"] = sorted(e["timelines"] or [])
    return found


def check_cursors(found, cursors):
    """What a latest-at viewer shows at each cursor, summed under its prefix."""
    problems = []
    for c in cursors:
        prefix, tl, at = norm(c["prefix"]), c["timeline"], c["at"]
        comp, depth = c["component"], c.get("depth", 1)
        total = 0
        for ent, e in found.items():
            if not (ent == prefix or ent.startswith(prefix + "/")):
                continue
            best = None
            for stamps, cc, dd, count in e["rows_of"]:
                v = stamps.get(tl)
                if cc != comp or dd != depth or v is None or v > at:
                    continue
                # Rows at the same stamp: the later one is drawn.
                if best is None or v >= best[0]:
                    best = (v, count)
            if best is not None:
                total += best[1]
        if total != c["want"]:
            problems.append(
                f"{prefix} at {tl} {at}: {total} {comp} (depth {depth}), want {c['want']}")
    return problems


def close(a, b):
    if isinstance(a, float) or isinstance(b, float):
        return abs(a - b) <= 1e-6 * max(1.0, abs(a), abs(b))
    return a == b


def check(found, expect):
    problems = []
    want_tls = set(expect.get("timelines", []))
    entities = {norm(k): v for k, v in expect.get("entities", {}).items()}
    for ent, want in entities.items():
        got = found.get(ent)
        if got is None:
            problems.append(f"{ent}: missing")
            continue
        if want.get("static", False):
            if got["static_rows"] != want.get("rows", got["static_rows"]):
                problems.append(f"{ent}: {got['static_rows']} static rows, want {want['rows']}")
            if got["rows"]:
                problems.append(f"{ent}: {got['rows']} temporal rows, want static only")
        else:
            if "rows" in want and got["rows"] != want["rows"]:
                problems.append(f"{ent}: {got['rows']} rows, want {want['rows']}")
            missing = set(want.get("timelines", want_tls)) - set(got["timelines"])
            if got["rows"] and missing:
                problems.append(f"{ent}: timelines {got['timelines']} lack {sorted(missing)}")
        for comp, n in want.get("instances", {}).items():
            have = got["instances"].get(comp)
            if have != n:
                problems.append(f"{ent}: {comp} has {have} instances, want {n}")
        for key in ("first", "last"):
            for tl, v in want.get(key, {}).items():
                have = got[key].get(tl)
                if have is None or not close(have, v):
                    problems.append(f"{ent}: {key} {tl} = {have}, want {v}")
    if expect.get("exact", False):
        extra = sorted(set(found) - set(entities))
        if extra:
            problems.append(f"unexpected entities: {extra}")
    return problems


def blueprint_origins(path):
    """The space origins of the views of the recording's stored blueprint."""
    reader = rrx.RrdReader(path)
    origins = set()
    for bp in reader.blueprints():
        for chunk in reader.stream(store=bp):
            rb = chunk.to_record_batch()
            for name in rb.schema.names:
                if name.endswith("space_origin"):
                    for v in rb.column(name).to_pylist():
                        vals = v if isinstance(v, list) else [v]
                        origins.update(norm(str(x)) for x in vals if x is not None)
    return sorted(origins)


def verify(path):
    """`rerun rrd verify` from the same package: the file loads and decodes."""
    proc = subprocess.run(
        [sys.executable, "-m", "rerun", "rrd", "verify", path],
        capture_output=True, text=True, stdin=subprocess.DEVNULL,
    )
    if proc.returncode != 0:
        return [f"rerun rrd verify failed ({proc.returncode}): {proc.stderr.strip()[-2000:]}"]
    return []


def main(argv):
    if len(argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    path, exp = argv[1], argv[2]
    expect = json.load(sys.stdin if exp == "-" else open(exp))
    problems = []
    want_version = expect.get("version")
    if want_version and rerun.__version__ != want_version:
        problems.append(f"rerun-sdk {rerun.__version__}, want {want_version}")
    cursors = expect.get("cursors", [])
    found = scan(path, cursors)
    problems += check(found, expect)
    problems += check_cursors(found, cursors)
    origins = blueprint_origins(path)
    for want in expect.get("blueprint", []):
        if norm(want) not in origins:
            problems.append(f"blueprint: no view of {want} (views of {origins})")
    problems += verify(path)
    for e in found.values():
        del e["rows_of"]
    summary = {"rerun_sdk": rerun.__version__, "entities": found, "blueprint": origins,
               "ok": not problems}
    print(json.dumps(summary, indent=1, sort_keys=True))
    for p in problems:
        print("MISMATCH", p, file=sys.stderr)
    return 0 if not problems else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))
