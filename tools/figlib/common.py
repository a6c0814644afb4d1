"""What every block of tools/figures.py shares: running odocal once per
command in a scratch folder, skipping what the data folder lacks, and the
number formats of the generated tables (docs/results/)."""
import concurrent.futures
import os
import statistics
import subprocess
import tempfile
import threading

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


class Skip(Exception):
    """A block that cannot be computed here (missing data), with the reason."""


class Runner:
    """Runs odocal commands once each, in a scratch folder, `jobs` at a time."""

    def __init__(self, odocal, data, scratch, jobs):
        self.odocal = odocal
        self.data = data
        self.scratch = scratch
        self.pool = concurrent.futures.ThreadPoolExecutor(max_workers=jobs)
        self.futures = {}
        self.lock = threading.Lock()

    def path(self, name):
        return os.path.join(self.scratch, name)

    def scratch_file(self, name, text):
        """`text` written to the scratch file `name`; its path."""
        path = self.path(name)
        with open(path, "w") as f:
            f.write(text)
        return path

    def call(self, args, allowed=(0,)):
        """Runs odocal with `args`; the finished process, or an error naming
        the command when its exit code is not among `allowed`."""
        cmd = [self.odocal] + [str(a) for a in args]
        p = subprocess.run(cmd, capture_output=True, text=True)
        if p.returncode not in allowed:
            raise RuntimeError(f"{' '.join(cmd)} failed ({p.returncode}):\n{p.stderr}")
        return p

    def run(self, args):
        """Runs odocal with `args`; its stdout (an error if it fails)."""
        return self.call(args).stdout

    def once(self, key, fn):
        """`fn()` started once per key in the pool; its future. The blocks
        ask from their own threads, and two runs of one command would write
        the same outputs."""
        with self.lock:
            if key not in self.futures:
                self.futures[key] = self.pool.submit(fn)
            return self.futures[key]

    def data_file(self, rel):
        """A file of the shared data folder; Skip when it is missing."""
        path = os.path.join(self.data, rel)
        if not os.path.isfile(path):
            raise Skip(f"{path} missing (set ODOCAL_DATA to the shared data folder)")
        return path


def spread(values, digits):
    """(median, `lo–hi`) at `digits` decimals; the range is None when every
    value prints alike."""
    r = span(values, digits)
    return num(statistics.median(values), digits), (r if "–" in r else None)


def num(x, digits):
    """`x` to `digits` decimals with a typographic minus."""
    return f"{x:.{digits}f}".replace("-", "−")


def span(values, digits):
    """`lo–hi` of `values` at `digits` decimals, one value when they print alike."""
    lo, hi = num(min(values), digits), num(max(values), digits)
    return lo if lo == hi else f"{lo}–{hi}"


def pm(v, se, scale, digits, unit, sign=False):
    """`v ± se unit`, both scaled, at `digits` decimals."""
    text = num(v * scale, digits)
    if sign and v > 0:
        text = "+" + text
    return f"{text} ± {num(se * scale, digits)} {unit}"


def percent(v, se):
    return pm(v, se, 100, 2 if se < 0.01 else 1, "%", sign=True)


def write_atomically(path, text):
    """`text` into `path` through a renamed temporary file (the file's mode
    kept; 0644 for a new one)."""
    mode = os.stat(path).st_mode & 0o777 if os.path.exists(path) else 0o644
    fd, tmp = tempfile.mkstemp(dir=os.path.dirname(path), prefix=".figures-")
    with os.fdopen(fd, "w") as f:
        f.write(text)
    os.chmod(tmp, mode)
    os.replace(tmp, path)
