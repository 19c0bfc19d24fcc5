"""Print the BSDF-level comparison reports against Mitsuba 3 (smooth and rough materials,
eval / pdf / sample, both sides); exit status 1 if any disagrees.

    python -m bsdflab.reference
"""
from __future__ import annotations

from bsdflab.reference.mitsuba_bsdf import compare_bsdf, standard_cases
from bsdflab.reference.mitsuba_rough import compare_rough, rough_cases


def main() -> int:
    failed = []
    cases = [(*c, compare_bsdf) for c in standard_cases()]
    cases += [(*c, compare_rough) for c in rough_cases()]
    for name, bsdf, wl, compare in cases:
        c = compare(bsdf, n_pairs=1000, seed=0, wavelength=wl)
        print(f"[{name}]\n{c.report()}\n")
        if not c.passed:
            failed.append(name)
    print(f"{len(cases) - len(failed)}/{len(cases)} agree with Mitsuba"
          + (f"; FAILED: {', '.join(failed)}" if failed else ""))
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
