"""Review of solve_snell: an independent PFMC z-test (pfmc2, 8000 walks per pair, 12 pairs
of all four kinds with grazing ones at 86-89 deg, 450/550/650 nm) on stacks the change's
tests do not cover: 2.0 -> 1.2 with a forward HG 0.8 slab below, an interface to 3.5,
three slabs with two unmatched interfaces, a strongly reflecting interior film (2.3,
70 nm) 1.4 -> 1.7 over water. Pass: |v - r| <= z s + e, Sidak family of every
(pair, wavelength) plus a sqrt(pairs) x mean-z test per case, alpha 0.01.
Measured (all four as one family): max z 2.04, 2.01, 1.65, 1.69 (limit 3.98); with the
interior film dropped from the solve the film case reads max z 8.71. CI runs two of the
four (SLOW_CASES below), each set its own family."""

import numpy as np
import pytest
from scipy import stats

import bsdflab as bl
from bsdflab.solvers import solve
from bsdflab.testing import random_unit_vectors, sidak_significance, spherical_directions

WL = [450.0, 550.0, 650.0]
KINDS = (("upper", "upper"), ("lower", "upper"), ("lower", "lower"), ("upper", "lower"))


def HG(d, g, sa=0.1, ss=0.5):
    return bl.Slab(d, sigma_a=sa, sigma_s=ss, phase={"type": "hg", "g": g})


ISO = lambda d=1.0, sa=0.2, ss=1.0: bl.Slab(d, sigma_a=sa, sigma_s=ss)
F = [{"material": 2.3, "thickness_nm": 70.0}]
cases = {
    "2.0 iso / 2.0->1.2 / HG 0.8 / to air": (
        lambda: bl.Layered(
            [bl.Dielectric(2.0, 1.0), bl.Dielectric(1.2, 2.0)],
            [ISO(0.5), HG(2.0, 0.8, 0.05, 1.0)],
            bl.Dielectric(1.0, 1.2),
        ),
        16,
    ),
    "1.5 HG.5 / 1.5->3.5 / iso / to air": (
        lambda: bl.Layered(
            [bl.Dielectric(1.5, 1.0), bl.Dielectric(3.5, 1.5)], [HG(1.0, 0.5), ISO()], bl.Dielectric(1.0, 3.5)
        ),
        16,
    ),
    "3 slabs 1.5/2.0/1.3 to air": (
        lambda: bl.Layered(
            [bl.Dielectric(1.5, 1.0), bl.Dielectric(2.0, 1.5), bl.Dielectric(1.3, 2.0)],
            [HG(1.0, 0.7), ISO(), HG(1.0, -0.3)],
            bl.Dielectric(1.0, 1.3),
        ),
        20,
    ),
    "1.4 iso / film 2.3 70nm 1.4->1.7 / HG.6 / to 1.33": (
        lambda: bl.Layered(
            [bl.Dielectric(1.4, 1.0), bl.Dielectric(1.7, 1.4, film=F)], [ISO(), HG(2.0, 0.6)], bl.Dielectric(1.33, 1.7)
        ),
        16,
    ),
}
# CI runs the interface to 3.5 and the interior film (2 of 4, the power case among them);
# the 2.0 -> 1.2 stack with its forward HG 0.8 slab (~12 CPU-s) and the three slabs (~7)
# are slow. Each set is its own Sidak family.
SLOW_CASES = {"2.0 iso / 2.0->1.2 / HG 0.8 / to air", "3 slabs 1.5/2.0/1.3 to air"}
FAM = (len(cases) - len(SLOW_CASES)) * (12 * len(WL) + 1)
SLOW_FAM = len(SLOW_CASES) * (12 * len(WL) + 1)
ZMAX = stats.norm.isf(sidak_significance(0.01, FAM) / 2)
SLOW_ZMAX = stats.norm.isf(sidak_significance(0.01, SLOW_FAM) / 2)
GRAZE = spherical_directions(np.radians([88.0, 86.0, 87.0, 89.0]), [0.5, 1.0, 2.0, 3.0])


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.slow) if n in SLOW_CASES else n for n in cases])
def test_matches_pfmc(name):
    """Mutation: Solution.eval_with_error's value x 1.02 fails it (the interior film case)."""
    mk, nodes = cases[name]
    wis = []
    wos = []
    for k, (hi, ho) in enumerate(KINDS):
        wi = random_unit_vectors(3, seed=101 + 2 * k, hemisphere=hi)
        wo = random_unit_vectors(3, seed=102 + 2 * k, hemisphere=ho)
        if k % 2:
            wi[0] = GRAZE[k] * [1, 1, 1 if hi == "upper" else -1]
        else:
            wo[0] = GRAZE[k] * [1, 1, 1 if ho == "upper" else -1]
        wis.append(wi)
        wos.append(wo)
    wi = np.concatenate(wis)
    wo = np.concatenate(wos)
    m = mk()
    model = bl.Layered(list(m.interfaces), list(m.slabs), m.base, estimator="pfmc2")
    est = model.estimate(wi, wo, wavelengths=WL, samples=8000, seed=7)
    sol = solve(model, WL, nodes=nodes)
    assert sol.two_sided
    r, e = sol.eval_with_error(wi, wo)
    z = (np.abs(est.value - r) - e) / est.stderr
    signed = (est.value - r) / np.hypot(est.stderr, e)
    mz = np.mean(signed) * np.sqrt(signed.shape[0])
    zmax = SLOW_ZMAX if name in SLOW_CASES else ZMAX
    print(f"{name}: max z {z.max():.2f}, sqrt(pairs) mean z {mz:.2f}, limit {zmax:.2f}")
    assert z.max() <= zmax and abs(mz) <= zmax
