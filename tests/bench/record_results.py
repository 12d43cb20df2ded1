#!/usr/bin/env python3
"""Writes one section of tests/bench/RESULTS.md: the benchmark scripts call this with their table on stdin.

    record_results.py --id ID --title TITLE --command CMD [--file RESULTS.md] < body.md

The section with the same id is replaced (others are kept, in their order; a new id is appended), headed by the
command that produced it, the machine it ran on and the commit it measured, so every figure in the file says where it
came from. RESULTS.md is written only this way, never by hand; earlier figures live in the logs beside it.
"""
import argparse
import os
import platform
import re
import subprocess
import sys

HEADER = """# Benchmark results

Every section below is written by the benchmark script or tool named in it (`tests/bench/record_results.py`
replaces the section of the same id), with the command, the machine and the commit it measured; nothing here is
edited by hand. Earlier figures and what was tried: the logs in tests/bench (`*_log.md`).
"""


def machine():
    model = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    model = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    load = ""
    try:
        load = f", load average {os.getloadavg()[0]:.1f}"
    except OSError:
        pass
    return f"{model}, {os.cpu_count()} cores{load}"


def commit(repo):
    try:
        out = subprocess.run(["git", "-C", repo, "describe", "--always", "--dirty", "--abbrev=10"],
                             capture_output=True, text=True, check=True)
        return out.stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown (not a git checkout)"


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--id", required=True, help="section id (other characters than letters, digits, _ - . and spaces "
                                                "become _)")
    ap.add_argument("--title", required=True)
    ap.add_argument("--command", required=True, help="the command that produced the figures")
    ap.add_argument("--file", default=os.path.join(here, "RESULTS.md"))
    args = ap.parse_args()
    args.id = re.sub(r"[^A-Za-z0-9_.\- ]", "_", args.id).strip()
    if not args.id:
        sys.exit("record_results.py: --id is empty (expected a section id)")
    body = sys.stdin.read().rstrip("\n")
    if not body:
        sys.exit("record_results.py: nothing on stdin (expected the section's table)")

    begin, end = f"<!-- BEGIN {args.id} -->", f"<!-- END {args.id} -->"
    section = "\n".join([
        begin,
        f"## {args.title}",
        "",
        f"- command: `{args.command}`",
        f"- machine: {machine()}",
        f"- commit: {commit(here)}",
        "",
        body,
        end,
    ])
    text = open(args.file).read() if os.path.exists(args.file) else HEADER
    pattern = re.compile(re.escape(begin) + r".*?" + re.escape(end), re.S)
    if pattern.search(text):
        text = pattern.sub(lambda _: section, text)
    else:
        text = text.rstrip("\n") + "\n\n" + section + "\n"
    tmp = args.file + ".tmp"
    with open(tmp, "w") as f:
        f.write(text if text.endswith("\n") else text + "\n")
    os.replace(tmp, args.file)
    print(f"record_results.py: section '{args.id}' written to {args.file}", file=sys.stderr)


if __name__ == "__main__":
    main()
