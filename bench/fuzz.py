"""Fuzzing the command line with mutated shipped scenarios: every file must get an answer.

``python -m bench.fuzz [--files 1000] [--seed 0]`` writes that many seeded
mutations of the shipped scenarios (see mutations.py; a quarter of them get a ROS map or SVG
plan, often broken, see map_mutations.py), then runs ``validate FILE`` and
``run FILE --headless --duration 2`` on each, in worker processes that are killed when a case
takes longer than ``--timeout`` seconds. It reports how many answers were fine (exit 0/1), bad
input told in one line (exit 2), tracebacks (exit 3, or a traceback on stderr, or a crashed
worker) and hangs. The target is 0 tracebacks and 0 hangs.
"""
from __future__ import annotations

import argparse
import contextlib
import copy
import io
import json
import os
import select
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path
from typing import IO

import numpy as np
import yaml

from bench.map_mutations import MAP_MUTATIONS
from bench.mutations import mutate

MEMORY_LIMIT = 2 << 30  # [bytes] per worker: a blow-up fails fast instead of swapping
RUN_SECONDS = "2"  # simulated seconds per `run`
SLOW_SECONDS = 10.0  # [s] wall: a command slower than this is counted (and named with -v)
MAP_SHARE = 0.25  # of the cases get a map file (a ROS map or an SVG plan, see map_mutations.py)


def write_cases(folder: Path, files: int, seed: int) -> list[tuple[Path, str]]:
    """``files`` mutated scenarios in ``folder``: (path, mutation name)."""
    from pymunk_bot.config.loader import shipped_scenarios

    bases = [yaml.safe_load(path.read_text()) for path in shipped_scenarios().values()]
    rng = np.random.default_rng(seed)
    cases = []
    for k in range(files):
        base = bases[int(rng.integers(len(bases)))]
        path = folder / f"case{k:05d}.yaml"
        if rng.random() < MAP_SHARE:
            mutation = MAP_MUTATIONS[int(rng.integers(len(MAP_MUTATIONS)))]
            name = mutation.__name__
            text, extra = mutation(copy.deepcopy(base), rng, path.stem)
            for file_name, content in extra.items():
                if content is None:
                    (folder / file_name).mkdir(exist_ok=True)
                else:
                    (folder / file_name).write_bytes(content)
        else:
            name, text = mutate(base, rng)
        path.write_text(text)
        cases.append((path, name))
    return cases


def classify(code: int | None, stderr: str) -> str:
    """ok | exit-2 | bad-message | traceback | hang, for one command's outcome."""
    if code is None:
        return "hang"
    if code == 3 or "Traceback" in stderr:
        return "traceback"
    if code == 2:
        lines = [line for line in stderr.splitlines() if not line.startswith("warning: ")]
        return "exit-2" if len(lines) == 1 and lines[0].startswith("error: ") else "bad-message"
    return "ok" if code in (0, 1) else "traceback"


class Worker:
    """A child process running CLI commands in-process, one JSON line per command."""

    def __init__(self) -> None:
        env = {**os.environ, "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy",
               "MPLBACKEND": "Agg"}
        self.proc = subprocess.Popen([sys.executable, "-m", "bench.fuzz",
                                      "--worker"], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     text=True, env=env)
        if self.proc.stdin is None or self.proc.stdout is None:
            raise RuntimeError("the fuzz worker process was started without its stdin/stdout pipes")
        self.stdin: IO[str] = self.proc.stdin
        self.stdout: IO[str] = self.proc.stdout

    def ask(self, argv: list[str], timeout: float) -> tuple[int | None, str]:
        """(exit status, stderr); (None, "") when it hangs; status 3 when the worker dies."""
        self.stdin.write(json.dumps(argv) + "\n")
        self.stdin.flush()
        ready, _, _ = select.select([self.stdout], [], [], timeout)
        if not ready:
            self.close()
            return None, ""
        line = self.stdout.readline()
        if not line:
            self.close()
            return 3, "Traceback: the worker process died"
        answer = json.loads(line)
        return answer["code"], answer["stderr"]

    def close(self) -> None:
        self.proc.kill()
        self.proc.wait()


def worker_loop() -> None:
    """Serve commands from stdin (run inside the worker process)."""
    try:
        import resource

        resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))
    except (ImportError, ValueError, OSError):
        pass
    from pymunk_bot.cli import main

    out = sys.stdout
    for line in sys.stdin:
        argv = json.loads(line)
        err = io.StringIO()
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
            try:
                code = main(argv)
            except SystemExit as exc:
                code = exc.code if isinstance(exc.code, int) else 2
            except BaseException:  # main() must not let anything out: that is a traceback
                import traceback

                traceback.print_exc(file=err)
                code = 3
        out.write(json.dumps({"code": code, "stderr": err.getvalue()}) + "\n")
        out.flush()


def fuzz(files: int = 1000, seed: int = 0, timeout: float = 20.0,
         verbose: bool = False) -> dict[str, Counter[str]]:
    """Counts of outcomes per command ("validate", "run"), plus examples of the bad ones."""
    counts: dict[str, Counter[str]] = {"validate": Counter(), "run": Counter()}
    worker = Worker()
    with tempfile.TemporaryDirectory(prefix="pymunk-bot-fuzz-") as tmp:
        cases = write_cases(Path(tmp), files, seed)
        for path, name in cases:
            for command in ("validate", "run"):
                argv = [command, str(path)] + (
                    ["--headless", "--duration", RUN_SECONDS] if command == "run" else [])
                if worker.proc.poll() is not None:
                    worker = Worker()
                started = time.perf_counter()
                code, stderr = worker.ask(argv, timeout)
                elapsed = time.perf_counter() - started
                outcome = classify(code, stderr)
                counts[command][outcome] += 1
                if elapsed > SLOW_SECONDS and code is not None:
                    counts[command]["slow"] += 1
                    if verbose:
                        print(f"slow: {command} {path.name} ({name}): {elapsed:.1f} s")
                if outcome in ("traceback", "hang", "bad-message") and verbose:
                    tail = stderr.strip().splitlines()[-1:] if stderr.strip() else [""]
                    print(f"{outcome}: {command} {path.name} ({name}): {tail[0][:200]}")
                if code is None:
                    worker = Worker()
    worker.close()
    return counts


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--files", type=int, default=1000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--timeout", type=float, default=20.0, help="[s] per command")
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("-v", "--verbose", action="store_true")
    args = parser.parse_args(argv)
    if args.worker:
        worker_loop()
        return 0
    started = time.perf_counter()
    counts = fuzz(args.files, args.seed, args.timeout, args.verbose)
    print(f"{args.files} mutated scenarios (seed {args.seed}) in "
          f"{time.perf_counter() - started:.0f} s")
    for command, counter in counts.items():
        print(f"  {command:<8} ok {counter['ok']}, exit-2 {counter['exit-2']}, "
              f"bad message {counter['bad-message']}, tracebacks {counter['traceback']}, "
              f"hangs {counter['hang']}, over {SLOW_SECONDS:g} s {counter['slow']}")
    bad = sum(c[k] for c in counts.values() for k in ("traceback", "hang", "bad-message"))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
