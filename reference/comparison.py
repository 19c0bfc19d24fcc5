"""Error metric and result record of a BSDF cross-check against a reference code.

Relative error of a value a against the reference value b, per channel, the largest over
channels:

    err = |a - b| / max(|b|, REL_FLOOR),    REL_FLOOR = 1e-6,

so values near zero are compared absolutely. Directions use the vector norm: for unit
vectors it is the length of the difference (about the angle between them, in radians).

Pairs that float32 cannot resolve to the target are reported apart, never dropped; how
they are found and bounded is in conditioning.py.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

REL_FLOOR = 1e-6
TARGET = 1e-5

# eval, pdf: of the pair (wi, wo); the rest: of the sample drawn for (wi, u1, u2).
QUANTITIES = ("eval", "pdf", "weight", "direction", "sample_pdf", "eta")
SAMPLE_QUANTITIES = ("weight", "direction", "sample_pdf", "eta")


def rel_error(a, b, floor: float = REL_FLOOR) -> np.ndarray:
    """Relative error of a against b, the largest over channels for each row. Shapes
    broadcast: a grey (N, 1) result against an RGB (N, 3) one compares channel-wise."""
    a, b = np.broadcast_arrays(np.asarray(a, float), np.asarray(b, float))
    err = np.abs(a - b) / np.maximum(np.abs(b), floor)
    return err.reshape(len(err), -1).max(axis=1) if err.ndim > 1 else err


def direction_error(a, b, floor: float = REL_FLOOR) -> np.ndarray:
    """|a - b| / max(|b|, floor) for rows of 3-vectors."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    return np.linalg.norm(a - b, axis=1) / np.maximum(np.linalg.norm(b, axis=1), floor)


def errors_between(a: dict, b: dict, compare_sample: np.ndarray) -> dict[str, np.ndarray]:
    """Per-pair errors of result set a against b (dicts with keys eval, pdf, wo, weight,
    sample_pdf, eta). Sample quantities only where ``compare_sample`` (0 elsewhere): a
    sample's direction or weight means nothing when the codes picked different lobes."""
    e = {"eval": rel_error(a["eval"], b["eval"]), "pdf": rel_error(a["pdf"], b["pdf"]),
         "weight": rel_error(a["weight"], b["weight"]),
         "direction": direction_error(a["wo"], b["wo"]),
         "sample_pdf": rel_error(a["sample_pdf"], b["sample_pdf"]),
         "eta": rel_error(a["eta"], b["eta"])}
    for key in SAMPLE_QUANTITIES:
        e[key] = np.where(compare_sample, e[key], 0.0)
    return e


@dataclass(frozen=True)
class IllConditionedGroup:
    """Pairs that float32 cannot resolve to the target, sharing one reason."""

    reason: str
    count: int
    max_error: dict[str, float]        # per quantity, over this group
    max_error_over_bound: float        # <= 1: every error within its float32 bound
    lobe_flips: int                    # samples whose lobe differs, within float32 rounding


@dataclass(frozen=True)
class Comparison:
    """bsdflab against a reference code on n_pairs random queries (see module doc)."""

    label: str                          # the BSDF, e.g. "Dielectric(int_ior=1.5, ...)"
    reference: str                      # e.g. "Mitsuba 3.9.1 (llvm_ad_rgb)"
    wavelength: float | None            # nm; None: bsdflab's sRGB output was compared
    n_pairs: int
    n_well_conditioned: int             # pairs well-conditioned in every quantity
    max_error: dict[str, float]         # per quantity, over the pairs where it is well-conditioned
    n_sampled: int                      # samples valid in both codes with the same lobe
    n_lobe_mismatch: int                # lobe types differ, not explained by float32
    n_validity_mismatch: int            # one code sampled, the other did not (unexplained)
    n_over_target: int                  # well-conditioned pairs with an error > target
    ill_conditioned: tuple[IllConditionedGroup, ...] = ()
    target: float = TARGET
    model_difference: str = ""          # an expected, documented non-float32 difference
    notes: tuple[str, ...] = ()
    quantities: tuple[str, ...] = QUANTITIES  # the keys of max_error, in report order
    n_well: dict[str, int] = field(default_factory=dict)  # per quantity: its well-conditioned pairs

    @property
    def eval_error(self) -> float:
        return self.max_error["eval"]

    @property
    def pdf_error(self) -> float:
        return self.max_error["pdf"]

    @property
    def weight_error(self) -> float:
        return self.max_error["weight"]

    @property
    def direction_error(self) -> float:
        return self.max_error["direction"]

    @property
    def passed(self) -> bool:
        """Well-conditioned pairs within target, the rest within their float32 bound, and
        every lobe type and sample validity in agreement (or explained by float32)."""
        return (self.n_over_target == 0 and self.n_lobe_mismatch == 0
                and self.n_validity_mismatch == 0
                and all(g.max_error_over_bound <= 1.0 for g in self.ill_conditioned))

    def report(self) -> str:
        wl = "sRGB" if self.wavelength is None else f"{self.wavelength:g} nm"
        errs = "  ".join(f"{q} {self.max_error[q]:.1e}"
                         + (f" ({self.n_well[q]})" if q in self.n_well else "")
                         for q in self.quantities)
        lines = [
            f"{self.label} @ {wl} vs {self.reference}",
            f"  {self.n_pairs} pairs, {self.n_well_conditioned} well-conditioned in float32 in "
            f"every quantity (target {self.target:.2g}, relative error floor {REL_FLOOR:g})",
            f"  max relative error where well-conditioned (pairs): {errs}",
            f"  samples compared {self.n_sampled}; lobe-type mismatches {self.n_lobe_mismatch}, "
            f"validity mismatches {self.n_validity_mismatch}, errors over target {self.n_over_target}",
        ]
        if self.model_difference:
            lines.append(f"  expected model difference: {self.model_difference}")
        for g in self.ill_conditioned:
            gerr = "  ".join(f"{q} {g.max_error[q]:.1e}" for q in self.quantities
                             if g.max_error[q] > 0)
            lines.append(f"  ill-conditioned, {g.reason}: {g.count} pairs; max error "
                         f"{gerr or '0'}; error/bound <= {g.max_error_over_bound:.2f}; "
                         f"lobe flips {g.lobe_flips}")
        lines.extend(f"  note: {n}" for n in self.notes)
        lines.append(f"  {'PASS' if self.passed else 'FAIL'}")
        return "\n".join(lines)


def assert_agrees(c: Comparison) -> None:
    """Raise AssertionError, with the report, unless ``c`` passed: every quantity's error
    on its well-conditioned pairs within the target, every ill-conditioned group within
    its float32 bound, and every pair accounted for (none dropped)."""
    problems = [] if c.passed else ["not passed"]
    problems += [f"{q} {c.max_error[q]:.1e} over the target" for q in c.quantities
                 if c.max_error[q] > c.target]
    problems += [f"'{g.reason}': error/bound {g.max_error_over_bound:.2f}"
                 for g in c.ill_conditioned if g.max_error_over_bound > 1.0]
    if c.n_well_conditioned + sum(g.count for g in c.ill_conditioned) != c.n_pairs:
        problems.append("pairs dropped")
    if problems:
        raise AssertionError("; ".join(problems) + "\n" + c.report())
