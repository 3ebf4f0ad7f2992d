"""Run every bad-input case and count the outcomes.

    python tests/bad_input/battery.py            # counts per module and in total
    python tests/bad_input/battery.py -v         # and every case that is not a clear error

Outcomes: clear (the expected FdiError subclass, message names the problem), unclear (an FdiError,
but another class or a message that does not name the problem), raw (a numpy/scipy/pyarrow/Python
exception or a traceback), silent (no error: a wrong result returned without complaint).
"""

from __future__ import annotations

import importlib.util
import sys
from collections import Counter
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from harness import outcome  # noqa: E402


def main(verbose: bool = False) -> Counter:
    total: Counter = Counter()
    for path in sorted(HERE.glob("test_*.py")):
        spec = importlib.util.spec_from_file_location(path.stem, path)
        module = importlib.util.module_from_spec(spec)
        try:
            spec.loader.exec_module(module)
        except Exception as exc:  # noqa: BLE001
            print(f"{path.name}: cannot import ({type(exc).__name__}: {exc})")
            continue
        counts: Counter = Counter()
        for c in getattr(module, "CASES", []):
            kind, detail = outcome(c)
            counts[kind] += 1
            if verbose and kind != "clear":
                print(f"  {kind:8s} {c.id}: {detail[:300]}")
        print(f"{path.name}: {sum(counts.values())} cases, " + ", ".join(f"{k} {v}" for k, v in sorted(counts.items())))
        total += counts
    print(f"total: {sum(total.values())} cases, " + ", ".join(f"{k} {v}" for k, v in sorted(total.items())))
    return total


if __name__ == "__main__":
    main(verbose="-v" in sys.argv)
