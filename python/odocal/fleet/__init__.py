"""Fleet calibration (``odocal fleet``) on this machine or on Ray.

``run(source, out)`` calibrates every recording of a fleet — a folder laid
out ``ROBOT/…/REC`` with a date ``YYYY-MM-DD`` in each path, or a manifest
CSV ``robot,path,start`` — and returns the summary ``odocal fleet --json``
prints: per robot the parameter trends and the alarms (``wear``, ``step``,
``fault``, ``insufficient``) with their evidence; ``fleet.csv``,
``fleet.json``, ``report.md`` and ``fleet.png`` go to ``out``.

``engine="local"`` runs on every core of this machine (Rust, rayon).
``engine="ray"`` makes each recording a Ray task that calls the same Rust
function; the plan (hashes, cache) and the report are made here, so both
engines give the same table. Results are cached in ``out/cache`` by the
recording's content hash and the settings: a re-run only calibrates new
files. On a cluster (``address="ray://host:10001"`` or ``"host:6379"``),
every node needs this package installed and the recordings and ``out`` at
the same paths (a shared filesystem).
"""

from __future__ import annotations

import json
import os
import sys
from typing import Any, Dict, List, Optional

from .. import _core

__all__ = ["run", "plan"]


def _settings(source, out, method, seed, robot, config) -> Dict[str, Any]:
    absolute = lambda p: None if p is None else os.path.abspath(os.fspath(p))  # noqa: E731
    bundled = robot is not None and not os.path.exists(os.fspath(robot))
    return dict(
        source=absolute(source),
        out=absolute(out),
        method=method,
        seed=seed,
        # A bundled robot's name (wheelchair, lego-robot, …) stays a name.
        robot=os.fspath(robot) if bundled else absolute(robot),
        config=absolute(config),
    )


def plan(source, out, *, method: Optional[str] = None, seed: Optional[int] = None,
         robot=None, config=None) -> Dict[str, Any]:
    """The fleet's recordings with their content hashes and cached results."""
    kw = _settings(source, out, method, seed, robot, config)
    return json.loads(_core.fleet_plan(**kw))


def _progress(done: int, total: int) -> None:
    if sys.stderr.isatty() or os.environ.get("ODOCAL_PROGRESS"):
        sys.stderr.write(f"\rfleet {done}/{total}")
        if done == total:
            sys.stderr.write("\n")
        sys.stderr.flush()


def _calibrate_task(item: str, kw: Dict[str, Any]) -> str:
    from odocal import _core as core  # imported in the Ray worker

    return core.fleet_calibrate(item, **kw)


def _on_ray(items: List[Dict[str, Any]], kw: Dict[str, Any], address: Optional[str],
            num_cpus: Optional[int]) -> List[Optional[Dict[str, Any]]]:
    try:
        import ray
    except ImportError as e:
        raise _core.InputError(
            f"engine='ray' needs Ray: pip install 'odocal[ray]' ({e})") from None
    started = not ray.is_initialized()
    if started:
        if address is None:
            ray.init(num_cpus=num_cpus, include_dashboard=False, log_to_driver=False)
        else:
            ray.init(address=address, log_to_driver=False)
    try:
        task = ray.remote(num_cpus=1)(_calibrate_task)
        # Neither cached nor a copy of an earlier recording (calibrated once).
        todo = [k for k, it in enumerate(items)
                if it["cached"] is None and it.get("same_as") is None]
        refs = {task.remote(json.dumps(items[k]), kw): k for k in todo}
        results: List[Optional[Dict[str, Any]]] = [None] * len(items)
        pending = list(refs)
        _progress(0, len(todo))
        while pending:
            ready, pending = ray.wait(pending, num_returns=1)
            for r in ready:
                results[refs[r]] = json.loads(ray.get(r))
            _progress(len(todo) - len(pending), len(todo))
        return results
    finally:
        if started:
            ray.shutdown()


def run(source, out, *, engine: str = "local", address: Optional[str] = None,
        num_cpus: Optional[int] = None, method: Optional[str] = None,
        seed: Optional[int] = None, robot=None, config=None) -> Dict[str, Any]:
    """Calibrate a fleet and raise its alarms (``odocal fleet``).

    ``engine``: ``"local"`` (every core here) or ``"ray"`` (one Ray task per
    recording; ``address`` joins a running cluster, else a local Ray is
    started with ``num_cpus`` CPUs). Returns the summary (the keys of
    ``odocal fleet --json``: ``alarms``, ``robots``, ``table``, …).
    """
    kw = _settings(source, out, method, seed, robot, config)
    if engine == "local":
        return json.loads(_core.fleet_run(**kw))
    if engine != "ray":
        raise _core.InputError(f"engine '{engine}': use 'local' or 'ray'")
    the_plan = json.loads(_core.fleet_plan(**kw))
    outcomes = _on_ray(the_plan["items"], kw, address, num_cpus)
    return json.loads(_core.fleet_finish(json.dumps(the_plan), json.dumps(outcomes), **kw))
