"""Long fuzz campaign: the properties of ``tests/fuzz/fuzz_properties.py``, one example per process.

Each case is one random example of one property (entry point), run in its own process
(forked from a parent that imported the library once) with one thread, a CPU-time and
an address-space limit (``resource.setrlimit``) and a wall-clock timeout, so a segmentation fault, a hang or a memory blow-up is caught
like an exception. Cases run one at a time, round-robin over the properties, seeds from
``--seed``. Every failure whose signature (property and the last lines of the error) is
new gets a reproducer in ``--out``: a shell command and the case it printed. A summary
goes to ``<out>/campaign.json``.

    python scripts/fuzz.py --cases 2000 --out fuzz_out            # the campaign
    python scripts/fuzz.py --repro symm_slic 1234                   # one case, in this process
"""

from __future__ import annotations

import argparse
import collections
import gc
import json
import os
import re
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
FUZZ_DIR = REPO / "tests" / "fuzz"

# seconds of wall clock per case, by property (whole solvers take longer); default 60
TIMEOUT = {"multiview_detect": 120, "run_options": 90}
# weights of the properties in the round-robin (COLMAP's cases are slow)
WEIGHT = {"multiview_detect": 1}


def _vm_bytes() -> int:
    """This process's current address space (Linux), 0 where unknown."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmSize:"):
                return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 0


def _load() -> dict:
    """The properties, with torch and the library imported (once, before any fork)."""
    sys.path[:0] = [str(REPO), str(FUZZ_DIR)]  # this checkout's torchsym
    import torch

    torch.set_num_threads(1)
    from fuzz_properties import PROPERTIES

    return PROPERTIES


def run_one(properties: dict, name: str, seed: int, memory_gb: float, cpu_s: int) -> None:
    """Run property ``name`` on the example of ``seed`` in this process, under limits of
    ``memory_gb`` more address space and ``cpu_s`` CPU seconds."""
    import resource

    from hypothesis import HealthCheck, Phase, settings
    from hypothesis import seed as hseed

    limit = _vm_bytes() + int(memory_gb * 2**30)
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    used = int(sum(resource.getrusage(resource.RUSAGE_SELF)[:2]))
    resource.setrlimit(resource.RLIMIT_CPU, (used + cpu_s, used + cpu_s + 5))
    # Hypothesis tries its minimal example first (the same for every seed, and quick): the
    # second example is the case drawn from the seed
    profile = settings(max_examples=2, derandomize=False, deadline=None, database=None, phases=[Phase.generate],
                       suppress_health_check=list(HealthCheck), print_blob=False)
    hseed(seed)(profile(properties[name]))()


def run_forked(properties: dict, name: str, seed: int, args: argparse.Namespace, log_path: Path) -> tuple[str, str, float]:
    """``(outcome, log, seconds)`` of one case in a forked child (the library is imported
    once in the parent; the child gets its own limits, output file and exit status)."""
    import signal

    t0 = time.perf_counter()
    sys.stdout.flush()
    sys.stderr.flush()
    gc.freeze()  # the parent's objects stay out of the child's collections: fewer copied pages
    pid = os.fork()
    if pid == 0:  # the child
        code = 1
        try:
            fd = os.open(log_path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
            os.dup2(fd, 1)
            os.dup2(fd, 2)
            run_one(properties, name, seed, args.memory_gb, args.cpu_s)
            code = 0
        except BaseException:
            import traceback

            traceback.print_exc()
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            os._exit(code)
    deadline = time.monotonic() + TIMEOUT.get(name, args.timeout)
    status = None
    while status is None:
        done, st_ = os.waitpid(pid, os.WNOHANG)
        if done:
            status = st_
        elif time.monotonic() > deadline:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
            status = -1
        else:
            time.sleep(0.02)
    log = log_path.read_text(errors="replace") if log_path.exists() else ""
    if status == -1:
        outcome = "timeout"
    elif os.WIFSIGNALED(status):
        outcome = f"killed (signal {os.WTERMSIG(status)})"
    else:
        outcome = "ok" if os.WEXITSTATUS(status) == 0 else "failed"
    if outcome != "ok" and ("MemoryError" in log or "Cannot allocate memory" in log):
        outcome = "memory"
    return outcome, log, time.perf_counter() - t0


def signature(name: str, outcome: str, log: str) -> str:
    """What makes two failures the same: the property, the outcome and the error's type
    and first frame in torchsym (line numbers and values dropped)."""
    lines = [ln for ln in log.splitlines() if ln.strip()]
    err = next((ln for ln in reversed(lines) if re.match(r"^[A-Za-z_.]+(Error|Exception|Interrupt)\b", ln.strip())), "")
    frames = re.findall(r'File "[^"]*/(torchsym/[^"]+)", line \d+, in (\w+)', log)
    where = f"{frames[-1][0]}:{frames[-1][1]}" if frames else ""
    return f"{name} | {outcome} | {err.split(':')[0].strip()} | {where}"


def campaign(args: argparse.Namespace) -> int:
    os.environ.update({"FUZZ_SHOW": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"})
    PROPERTIES = _load()
    names = [n for n in (args.only or PROPERTIES) for _ in range(WEIGHT.get(n, 3))]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    state_path = out / "campaign.json"
    state = json.loads(state_path.read_text()) if state_path.exists() else {"cases": 0, "by_property": {}, "failures": {}}
    t_end = time.time() + args.hours * 3600
    counts = collections.Counter()
    for i in range(args.cases):
        if time.time() > t_end:
            break
        name = names[i % len(names)]
        seed = args.seed + i
        outcome, log, seconds = run_forked(PROPERTIES, name, seed, args, out / "last_case.log")
        by = state["by_property"].setdefault(name, {"cases": 0, "failures": 0, "seconds": 0.0})
        by["cases"] += 1
        by["seconds"] = round(by["seconds"] + seconds, 1)
        state["cases"] += 1
        counts[outcome] += 1
        if outcome != "ok":
            by["failures"] += 1
            sig = signature(name, outcome, log)
            fail = state["failures"].setdefault(sig, {"count": 0, "first": [name, seed]})
            fail["count"] += 1
            if fail["count"] == 1:  # a new failure: its reproducer
                case = [ln for ln in log.splitlines() if ln.startswith("CASE")]
                repro = out / f"repro_{name}_{seed}.txt"
                repro.write_text(
                    f"# {sig}\n# rerun: PYTHONPATH=. python scripts/fuzz.py --repro {name} {seed}\n"
                    + "\n".join(case[-1:]) + "\n\n" + log[-6000:]
                )
                print(f"[{i}] NEW {sig} -> {repro}", flush=True)
        if (i + 1) % 50 == 0:
            print(f"[{i + 1}] {dict(counts)}", flush=True)
            state_path.write_text(json.dumps(state, indent=1))
    state_path.write_text(json.dumps(state, indent=1))
    (out / "campaign.md").write_text(report(state, args))
    print(f"done: {state['cases']} cases, {dict(counts)}, {len(state['failures'])} distinct failures", flush=True)
    return 0 if not state["failures"] else 1


def report(state: dict, args: argparse.Namespace) -> str:
    """The campaign as a markdown table: cases and failures by property, distinct failures."""
    lines = [
        "# Fuzz campaign (issue 50)",
        "",
        f"`python scripts/fuzz.py --cases {args.cases} --seed {args.seed}` (one forked process per case, 1 thread, "
        f"{args.cpu_s} CPU s, {args.memory_gb:g} GB more address space, {args.timeout} s wall), properties of "
        "`tests/fuzz/fuzz_properties.py`; load: " + ", ".join(f"{x:.1f}" for x in os.getloadavg()) + " at the end (2 cores shared).",
        "",
        f"{state['cases']} cases, {sum(f['count'] for f in state['failures'].values())} failed, "
        f"{len(state['failures'])} distinct failures.",
        "",
        "| property | cases | failures | mean s per case |",
        "|---|---|---|---|",
    ]
    for name, by in sorted(state["by_property"].items()):
        lines.append(f"| {name} | {by['cases']} | {by['failures']} | {by['seconds'] / max(by['cases'], 1):.2f} |")
    if state["failures"]:
        lines += ["", "| failure | count | first (property, seed) |", "|---|---|---|"]
        lines += [f"| {sig.replace(' | ', ' / ')} | {f['count']} | {f['first'][0]} {f['first'][1]} |" for sig, f in state["failures"].items()]
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=2000)
    ap.add_argument("--seed", type=int, default=0, help="seed of the first case (case i has seed + i)")
    ap.add_argument("--out", default="fuzz_out")
    ap.add_argument("--only", nargs="*", help="properties to run (default: all)")
    ap.add_argument("--timeout", type=int, default=60, help="wall seconds per case")
    ap.add_argument("--cpu-s", type=int, default=60, help="CPU seconds per case (RLIMIT_CPU)")
    ap.add_argument("--memory-gb", type=float, default=4.0, help="address space per case (RLIMIT_AS)")
    ap.add_argument("--hours", type=float, default=24.0, help="stop starting cases after this long")
    ap.add_argument("--repro", nargs=2, metavar=("PROPERTY", "SEED"), help="run one case here, with its traceback")
    args = ap.parse_args(argv)
    if args.repro:
        name, seed = args.repro
        os.environ["FUZZ_SHOW"] = "1"
        run_one(_load(), name, int(seed), args.memory_gb, args.cpu_s)
        return 0
    return campaign(args)


if __name__ == "__main__":
    sys.exit(main())
