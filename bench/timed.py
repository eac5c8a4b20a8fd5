#!/usr/bin/env python3
"""Wall time, CPU time and peak memory of one command, as GNU time's "%e %U %S %M" gives them, without
GNU time (Debian's `time` package is optional: a fresh Debian 12 does not have /usr/bin/time).

    python3 bench/timed.py -o FILE COMMAND [ARGS...]   writes "WALL USER SYS MAXRSS_KB" to FILE
    from timed import run_timed                         (WALL, USER, SYS, MAXRSS_KB) of a command

The CPU times and the peak are the command's resource usage as wait4 reports it: the user and system
time of the command and of every descendant it waited for (city3d's CBC processes), and the largest peak
resident set among them, in KB. A process's peak counts the memory of the process it was started from
until it execs, so run_timed() measures through this small script as GNU time does: a large caller
(synthetic_tile.py holds the tile it made) would otherwise show its own peak. A command that fails is
an error (its exit status is passed on).
"""
import os
import subprocess
import sys
import tempfile
import time


def run_timed(command, **popen_args):
    """(wall s, user s, sys s, peak RSS KB) of `command`; raises CalledProcessError when it fails."""
    with tempfile.NamedTemporaryFile("r") as result:
        try:
            subprocess.run([sys.executable, os.path.abspath(__file__), "-o", result.name, *command], check=True,
                           **popen_args)
        except subprocess.CalledProcessError as e:
            raise subprocess.CalledProcessError(e.returncode, command) from None
        wall, user, system, kb = result.read().split()
    return float(wall), float(user), float(system), int(kb)


def main():
    if len(sys.argv) < 4 or sys.argv[1] != "-o":
        sys.exit("usage: timed.py -o FILE COMMAND [ARGS...]")
    command = sys.argv[3:]
    start = time.monotonic()
    try:
        proc = subprocess.Popen(command)
    except OSError as e:
        sys.exit(f"timed.py: cannot run {command[0]}: {e.strerror}")
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.monotonic() - start
    code = os.waitstatus_to_exitcode(status)
    if code != 0:
        sys.exit(code if code > 0 else 1)
    with open(sys.argv[2], "w") as f:
        f.write(f"{wall:.2f} {usage.ru_utime:.2f} {usage.ru_stime:.2f} {usage.ru_maxrss}\n")


if __name__ == "__main__":
    main()
