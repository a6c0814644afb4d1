"""Type stubs of the extension module (each function returns the JSON of the
command line's ``--json``, except ``read``)."""

from typing import Any, Dict, List, Optional

__version__: str

class InputError(ValueError):
    """Bad input or arguments: the command line's exit-2 message."""

class OutputError(OSError):
    """An output could not be written: the command line's exit 1."""

def read(path: str, robot: Optional[str] = None, config: Optional[str] = None) -> Dict[str, Any]: ...
def icp(input: str, out: str, motions: Optional[str] = None, robot: Optional[str] = None,
        config: Optional[str] = None) -> str: ...
def calibrate(out: str, input: Optional[str] = None, motions: Optional[str] = None,
              wheels: Optional[str] = None, method: Optional[str] = None,
              resampler: Optional[str] = None, trigger: Optional[str] = None,
              particles: Optional[int] = None, seed: Optional[int] = None,
              robot: Optional[str] = None, config: Optional[str] = None,
              init: Optional[str] = None) -> str: ...
def eval(estimate: str, reference: Optional[str] = None, relations: Optional[str] = None,
         align: Optional[str] = None, t_max_diff: Optional[float] = None,
         t_offset: Optional[float] = None, interpolate: bool = False,
         resample_reference: Optional[bool] = None, max_gap: Optional[float] = None,
         rpe_delta: Optional[float] = None, rpe_unit: Optional[str] = None,
         plot: Optional[str] = None, robot: Optional[str] = None,
         config: Optional[str] = None) -> str: ...
def diagnose(measured: str, holdout: Optional[float] = None, report: Optional[str] = None,
             robot: Optional[str] = None, config: Optional[str] = None) -> str: ...
def simulate(out: str, scenario: Optional[str] = None, seed: Optional[int] = None,
             duration: Optional[float] = None, effects: List[str] = ...,
             truth: Optional[str] = None, robot: Optional[str] = None,
             config: Optional[str] = None, start: Optional[str] = None) -> str: ...
def fleet_run(source: str, out: str, method: Optional[str] = None, seed: Optional[int] = None,
              robot: Optional[str] = None, config: Optional[str] = None) -> str: ...
def fleet_plan(source: str, out: str, method: Optional[str] = None, seed: Optional[int] = None,
               robot: Optional[str] = None, config: Optional[str] = None) -> str: ...
def fleet_calibrate(item: str, source: str, out: str, method: Optional[str] = None,
                    seed: Optional[int] = None, robot: Optional[str] = None,
                    config: Optional[str] = None) -> str: ...
def fleet_finish(plan: str, outcomes: str, source: str, out: str, method: Optional[str] = None,
                 seed: Optional[int] = None, robot: Optional[str] = None,
                 config: Optional[str] = None) -> str: ...
