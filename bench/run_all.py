#!/usr/bin/env python3
"""`make bench`: runs every bench/<tool>*_benchmark.py (each writes its tables and plots
into docs/) in name order, or only those whose name contains an argument."""

import glob
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def main():
    wanted = sys.argv[1:]
    scripts = sorted(glob.glob(os.path.join(ROOT, "bench", "*_benchmark.py")))
    scripts = [s for s in scripts if not wanted or any(w in os.path.basename(s) for w in wanted)]
    failed = []
    for script in scripts:
        print(f"=== {os.path.basename(script)} ===", flush=True)
        if subprocess.run([sys.executable, script], cwd=ROOT).returncode != 0:
            failed.append(os.path.basename(script))
    if failed:
        sys.exit(f"benchmarks failed: {', '.join(failed)}")


if __name__ == "__main__":
    main()
