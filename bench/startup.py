#!/usr/bin/env python3
"""What every run of city3d pays before its first building: the shared libraries it loads and the CPU
of starting (`city3d --version`), and a run of one small building (../shared/data/city3d_smoke/AHN3/
19960.ply, 1,252 points), whose CPU the start dominates. With --baseline, the two builds run in
alternation and the ratios are taken pair by pair (the machine's speed drifts).

    python3 bench/startup.py [--city3d build/city3d] [--baseline OTHER/city3d] [--runs 21]

Needs python3 and ldd (libc-bin) only. CPU is user + system of the process as wait4 reports it; peak is
its largest resident set.
"""
import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
BUILDING = os.path.normpath(os.path.join(HERE, "..", "..", "shared", "data", "city3d_smoke", "AHN3", "19960.ply"))


def libraries(binary):
    out = subprocess.run(["ldd", binary], capture_output=True, text=True, check=True).stdout
    return sum(1 for line in out.splitlines() if line.strip())


def run(command):
    """(CPU s, peak MB) of one run of `command`, its output thrown away."""
    proc = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    _, status, usage = os.wait4(proc.pid, 0)
    if os.waitstatus_to_exitcode(status) != 0:
        sys.exit(f"startup.py: {' '.join(command)} failed")
    return usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024


def commands(name, binary, work):
    out = os.path.join(work, name)
    return {
        "--version": [binary, "--version"],
        "one building": [binary, "reconstruct", BUILDING, "-o", out, "--no-progress", "-q", "--no-resume"],
    }


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--city3d", default=os.path.join(HERE, "..", "build", "city3d"))
    p.add_argument("--baseline", help="another city3d binary, run in alternation")
    p.add_argument("--runs", type=int, default=21)
    a = p.parse_args()
    if not os.path.exists(BUILDING):
        sys.exit(f"startup.py: {BUILDING} not found (../shared/data beside the repository)")
    binaries = {"city3d": a.city3d}
    if a.baseline:
        binaries["baseline"] = a.baseline
    for name, binary in binaries.items():
        if not (os.path.isfile(binary) and os.access(binary, os.X_OK)):
            sys.exit(f"startup.py: no executable at {binary}")
        print(f"{name} ({binary}): {libraries(binary)} shared libraries loaded")
    work = tempfile.mkdtemp(prefix="city3d_startup_")
    try:
        results = {name: {what: [] for what in commands(name, b, work)} for name, b in binaries.items()}
        for _ in range(a.runs):
            for name, binary in binaries.items():
                for what, command in commands(name, binary, work).items():
                    results[name][what].append(run(command))
        for what in commands("city3d", a.city3d, work):
            for name in binaries:
                cpu = statistics.median(r[0] for r in results[name][what])
                peak = statistics.median(r[1] for r in results[name][what])
                print(f"{what:13s} {name:8s}: CPU {cpu * 1000:.1f} ms, peak {peak:.1f} MB (medians of {a.runs})")
            if a.baseline:
                ratios = [c[0] / b[0] for c, b in zip(results["city3d"][what], results["baseline"][what]) if b[0] > 0]
                print(f"{what:13s} city3d / baseline CPU, pair by pair: median {statistics.median(ratios):.2f}")
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
