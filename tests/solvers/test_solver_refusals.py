"""Every stack bsdflab.Layered (PFMC) accepts is either solved by adding-doubling or refused
with a ValueError naming its gap code (bsdflab.solvers.adding_doubling.GAPS;
docs/solvers.md, "Solved and refused"): never a crash, never a non-finite value.

The enumeration: every top (smooth, smooth + film, GGX, GGX + film, Beckmann multiscatter,
a roughness below the validated range) on every base
(Lambertian, smooth conductor + film, rough conductor, smooth and rough dielectric to water,
spectral and RGB measured files, a MERL file, a table); every interior interface (smooth
matched, with a film, unmatched to a lower and a higher index, unmatched with a film; rough,
with and without a film: Layered refuses a matched rough one) over an opaque, a smooth and a
rough transmissive base; every slab phase (isotropic, HG, HG beyond the range, von
Mises-Fisher, non-scattering). A stack counts only where PFMC itself evaluates it. Each
solved stack is queried with all four kinds of pairs (reflection from above and below,
transmission down and up, grazing ones included): values
finite, and those of an opaque stack below it exactly 0. The expected outcome is stated here
from the configuration, not read from the solver.

Cost: each top and base is built once and shared by every stack it joins (a multiscatter
top's and a MERL base's core set-up, ~2-3 s, is cached on the instance), and every solve
runs at ``ORDERS`` Fourier orders: this file checks outcomes and finiteness, not accuracy
(at the automatic orders, 62 for the alpha 0.1 top over a rough base, that one stack took
190 s of test_01's ~300 s at load ~22; the z-tests of tests/solvers solve at them). The four
kinds of pairs are asked in one eval (a rough base's exits cost ~0.5 s a call, not a pair:
test_01 19.0 -> 10.7 CPU-s, test_02 12.7 -> 4.4). Mutation checked: dropping the
``rough-exit`` refusal of Solution._pairs fails test_02[smooth-smooth unmatched].
Mutation: negating Solution.eval for wi.z < 0 fails test_01 (its "down" pairs)."""

from __future__ import annotations

import re

import numpy as np
import pytest

import bsdflab as bl
from bsdflab.measured import export_model
from bsdflab.measured.merl import DIMS, merl_bytes
from bsdflab.solvers import solve
from bsdflab.solvers.adding_doubling import GAPS
from bsdflab.tables import TableBSDF
from bsdflab.testing import spherical_directions
from tests.support.tables import valid_table

WL = [450.0, 550.0, 650.0]
FILM = [{"material": 1.83, "thickness_nm": 300.0}]
ISO = bl.Slab(1.0, sigma_a=0.2, sigma_s=1.0)
ORDERS = 8  # Fourier orders of every solve here (module docstring: outcomes, not accuracy)

# name -> (top, rough, expected stack-wide gap or None)
TOPS = {
    "smooth": (lambda: bl.Dielectric(1.5, 1.0), False, None),
    "smooth film": (lambda: bl.Dielectric(1.5, 1.0, film=FILM), False, None),
    "ggx 0.2": (lambda: bl.RoughDielectric(0.2, 1.5, 1.0), True, None),
    "ggx 0.1 film": (lambda: bl.RoughDielectric(0.1, 1.5, 1.0, film=FILM), True, None),
    "beckmann 0.4 multiscatter": (
        lambda: bl.RoughDielectric(0.4, 1.5, 1.0, distribution="beckmann", multiscatter=True),
        True,
        None,
    ),
    "ggx 5e-4 (below range)": (lambda: bl.RoughDielectric(5e-4, 1.5, 1.0), True, "alpha-range"),
}


def _bases(folder):
    spectral, rgb, merl = folder / "cu_spec.bsdf", folder / "cu_rgb.bsdf", folder / "grey.binary"
    cu = bl.RoughConductor(alpha=0.3, material="Cu")
    export_model(cu, spectral, wavelengths=WL, n_theta_i=6, resolution=16, error_points=200)
    export_model(cu, rgb, n_theta_i=6, resolution=16, error_points=200)
    merl.write_bytes(merl_bytes(np.full((3, *DIMS), 0.1)))
    # name -> (base, transmissive, rough, expected stack-wide gap or None)
    bases = {
        "diffuse": (lambda: bl.Diffuse(0.5), False, False, None),
        "conductor film": (lambda: bl.Conductor(material="Au", ext_ior=1.5, film=FILM), False, False, None),
        "roughconductor": (lambda: bl.RoughConductor(0.3, material="Cu", ext_ior=1.5), False, True, None),
        "dielectric to water": (lambda: bl.Dielectric(1.33, 1.5), True, False, None),
        "roughdielectric to water": (lambda: bl.RoughDielectric(0.3, 1.33, 1.5), True, True, None),
        "measured spectral": (lambda: bl.Measured(spectral), False, True, None),
        "measured rgb": (lambda: bl.Measured(rgb), False, True, "rgb-base"),
        "merl": (lambda: bl.Merl(merl), False, True, "rgb-base"),
        "table": (lambda: TableBSDF(valid_table()), False, True, "base-kind"),
    }
    # one instance each, shared by every top (module docstring)
    return {name: (shared(make), *rest) for name, (make, *rest) in bases.items()}


def shared(make):
    """A factory answering one instance of ``make()`` every time."""
    instance = make()
    return lambda: instance


# name -> (interface below slab 0 (top of slab 1), its lower index, expected gap under a
# rough top or None; under a smooth top every one is solved)
INTERIORS = {
    "smooth matched": (lambda: bl.Dielectric(1.5, 1.5), 1.5, None),
    "smooth matched film": (lambda: bl.Dielectric(1.5, 1.5, film=FILM), 1.5, None),
    "smooth unmatched": (lambda: bl.Dielectric(1.3, 1.5), 1.3, "smooth-interior-rough-top"),
    "smooth unmatched film": (lambda: bl.Dielectric(1.3, 1.5, film=FILM), 1.3, "smooth-interior-rough-top"),
    "smooth unmatched denser": (lambda: bl.Dielectric(2.0, 1.5), 2.0, "smooth-interior-rough-top"),
    "rough film": (lambda: bl.RoughDielectric(0.4, 1.3, 1.5, film=FILM), 1.3, None),
    "rough unmatched": (lambda: bl.RoughDielectric(0.5, 2.0, 1.5), 2.0, None),
}
INTERIOR_BASES = {  # lower index -> base; transmissive, rough
    "diffuse": (lambda n: bl.Diffuse(0.5), False, False),
    "dielectric to air": (lambda n: bl.Dielectric(1.0, n), True, False),
    "roughdielectric to air": (lambda n: bl.RoughDielectric(0.3, 1.0, n), True, True),
}
PHASES = {
    "isotropic": (bl.Slab(1.0, sigma_a=0.2, sigma_s=1.0), None),
    "hg 0.6": (bl.Slab(1.0, sigma_a=0.2, sigma_s=1.0, phase={"type": "hg", "g": 0.6}), None),
    "hg -0.3": (bl.Slab(1.0, sigma_a=0.2, sigma_s=1.0, phase={"type": "hg", "g": -0.3}), None),
    "hg 0.97 (beyond range)": (bl.Slab(1.0, sigma_a=0.2, sigma_s=1.0, phase={"type": "hg", "g": 0.97}), "hg-range"),
    "vmf": (bl.Slab(1.0, sigma_a=0.2, sigma_s=1.0, phase={"type": "vmf", "kappa": 5.0}), "phase-kind"),
    "clear": (bl.Slab(1.0, sigma_a=0.2, sigma_s=0.0), None),
}


def pairs():
    """(kind, wi, wo) for the four kinds, a grazing direction (87 deg) in each."""
    up = spherical_directions(np.radians([20.0, 87.0, 55.0]), [0.0, 1.0, 2.5])
    wo = spherical_directions(np.radians([40.0, 30.0, 87.0]), [2.0, 0.3, 4.0])
    flip = np.array([1.0, 1.0, -1.0])
    return {"above": (up, wo), "down": (up * flip, wo), "up": (up, wo * flip), "below": (up * flip, wo * flip)}


def pfmc_accepts(model) -> bool:
    """Whether PFMC evaluates the stack (what the solver owes an answer for)."""
    try:
        model.estimate(*pairs()["above"], wavelengths=WL, samples=4)
    except ValueError:
        return False
    return True


def check(model, expected: set, transmissive: bool, rough_exit: bool, scatters: bool = True) -> str:
    """Solve ``model`` (or see it refused) and check the outcome against ``expected`` (the
    gap codes it may be refused with; empty: it must be solved). Returns the outcome.
    ``rough_exit``: the stack's pairs below are refused (a rough base under a smooth
    interior interface between unequal indices), when it transmits.
    ``scatters`` False: every path is specular, so eval (no delta lobes) is 0 everywhere."""
    assert pfmc_accepts(model)
    try:
        sol = solve(model, WL, nodes=8, fine_step=1.0, orders=ORDERS)
    except ValueError as e:
        code = re.search(r"\[([a-z-]+)\]", str(e))
        assert code and code.group(1) in expected, f"refused with an unexpected reason: {e}"
        assert GAPS[code.group(1)] in str(e)
        return f"refused [{code.group(1)}]"
    assert not expected, f"solved, but expected a refusal {expected}"
    kinds = pairs()
    if transmissive and rough_exit:
        for kind in ("down", "up", "below"):
            with pytest.raises(ValueError, match=r"\[rough-exit\]"):
                sol.eval(*kinds[kind])
        kinds = {"above": kinds["above"]}
    # every kind answered by one eval (a rough base's exits cost a set-up per call, ~0.5 s,
    # not per pair), split back per kind; each pair's value is the same as alone
    n = len(kinds["above"][0])
    values = sol.eval(np.concatenate([wi for wi, _ in kinds.values()]),
                      np.concatenate([wo for _, wo in kinds.values()]))
    for i, (kind, (wi, _wo)) in enumerate(kinds.items()):
        v = values[i * n:(i + 1) * n]
        assert v.shape == (len(wi), len(WL)) and np.all(np.isfinite(v)), kind
        if not scatters:
            assert np.all(v == 0.0), f"{kind}: a purely specular stack has no eval"
        elif kind == "above" or transmissive:
            assert np.all(v >= 0) and np.any(v > 0), kind
        else:
            assert np.all(v == 0.0), f"an opaque stack's {kind} pairs must be 0"
    return "solved"


@pytest.fixture(scope="module")
def bases(tmp_path_factory):
    return _bases(tmp_path_factory.mktemp("bases"))


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_01_every_top_on_every_base(bases):
    outcomes = {}
    for tname, (make_top, _top_rough, top_gap) in TOPS.items():
        top = shared(make_top)
        for bname, (base, transmissive, _base_rough, base_gap) in bases.items():
            model = bl.Layered([top()], [ISO], base())
            if not pfmc_accepts(model):
                outcomes[tname, bname] = "not accepted by PFMC"
                continue
            expected = {g for g in (top_gap, base_gap) if g}
            # every top over a smooth or rough dielectric base is solved on every pair
            outcomes[tname, bname] = check(model, expected, transmissive, False)
    for key, outcome in outcomes.items():
        print(key, outcome)
    assert sum(o == "solved" for o in outcomes.values()) >= 30


@pytest.mark.filterwarnings("ignore::UserWarning")
@pytest.mark.parametrize("interior", list(INTERIORS))
@pytest.mark.parametrize("top", ["smooth", "ggx 0.2"])
def test_02_interior_interfaces(interior, top):
    make, n_below, gap = INTERIORS[interior]
    for base, transmissive, base_rough in INTERIOR_BASES.values():
        model = bl.Layered([TOPS[top][0](), make()], [ISO, ISO], base(n_below))
        # a rough base's exits are refused below a smooth unmatched interface (the
        # interfaces with a gap under a rough top, which refuses them at solve); a smooth
        # base's never
        check(model, {gap} - {None} if TOPS[top][1] else set(), transmissive, base_rough and gap is not None)


@pytest.mark.filterwarnings("ignore::UserWarning")
@pytest.mark.parametrize("phase", list(PHASES))
def test_03_slab_phases(phase):
    slab, gap = PHASES[phase]
    for base, transmissive in ((bl.Diffuse(0.5), False), (bl.Dielectric(1.0, 1.5), True)):
        model = bl.Layered([bl.Dielectric(1.5, 1.0)], [slab], base)
        check(model, {gap} - {None}, transmissive, False, scatters=slab.sigma_s > 0 or not transmissive)


def test_04_not_layered_and_conductor_tops():
    """A model that is no stack is refused by code; a conductor top is refused by Layered
    itself (PFMC does not accept it either), the message saying why (an opaque top hides
    the stack) and pointing to the film-coated conductor as the material; a conductor
    below the top is pointed to the base."""
    with pytest.raises(ValueError, match=r"\[not-layered\]"):
        solve(bl.Diffuse(0.5), WL)
    for top in (bl.Conductor(material="Au", film=FILM), bl.RoughConductor(0.3, material="Cu")):
        with pytest.raises(ValueError, match=r"interfaces\[0\] must be a dielectric.*conductor top is opaque and "
                                             r"hides every layer below it.*film=\[\.\.\.\] for a coated metal"):
            bl.Layered([top], [ISO], bl.Diffuse(0.5))
    with pytest.raises(ValueError, match=r"interfaces\[1\] must be a dielectric.*make it the base"):
        bl.Layered([bl.Dielectric(1.5, 1.0), bl.Conductor(material="Au")], [ISO, ISO], bl.Diffuse(0.5))
    # the material that message points to: the film-coated conductor, evaluated as itself
    coated = bl.Conductor(material="Au", film=FILM)
    wi, wo = pairs()["above"]
    assert np.all(np.isfinite(coated.eval(wi, wo, wavelengths=WL)))
