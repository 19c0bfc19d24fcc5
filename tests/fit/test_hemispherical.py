"""Total rows of the full model (bsdflab.fit.hemispherical): the directional-hemispherical
reflectance of a solved stack, the rough top's reflection by its own half-vector rule.

References, independent of the rule: a brute midpoint grid over the detector's hemisphere
(the top's part, where the eval is cheap), the model's own importance sampling
(``Layered.sample``: reflected weights' mean is R; PFMC, not the adding-doubling solver),
and the rule at 4x the nodes (its truncation). The Monte Carlo comparisons are z-tests at a
family alpha of 0.01, Sidak-corrected over the 6 (angle, wavelength) values: |z| < 3.14
(the channels share walks, so the family is positively dependent and Sidak conservative).
Mutation run once: dropping the top's part (``directional_albedo`` returning the scattered
part alone) fails the Monte Carlo test at z = -325 (8 deg, 550 nm)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import norm

from bsdflab.bsdfs import from_dict
from bsdflab.fit import hemispherical as H
from bsdflab.fit.data import GEOMETRIES, Dataset
from bsdflab.fit.full_stack_config import FullStackConfig
from bsdflab.fit.full_stack_forward import StructureSolverForward
from bsdflab.lobes import Lobe
from bsdflab.solvers import solve

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "fit" / "structure_full"
_spec = importlib.util.spec_from_file_location("make_structure_full_data", EXAMPLE / "make_data.py")
make_data = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(make_data)

WAVES = np.array([450.0, 550.0, 650.0])
TRUTH = {"roughness": 0.12, "sigma_s": 0.4, "base_albedo": 0.35}
Z = norm.isf((1 - (1 - 0.01) ** (1 / 6)) / 2)  # 3.14


def model(**over):
    d = make_data.truth_model({**TRUTH, **over})
    return from_dict(d), d


def brute_top(top, theta_deg: float) -> np.ndarray:
    """The top's reflectance by a 1000 x 600 midpoint grid in (theta_d, phi_d in [0, pi])."""
    nt, nphi = 1000, 600
    t = (np.arange(nt) + 0.5) * (np.pi / 2) / nt
    p = (np.arange(nphi) + 0.5) * np.pi / nphi
    tt, pp = np.meshgrid(t, p, indexing="ij")
    d = np.stack([np.sin(tt) * np.cos(pp), np.sin(tt) * np.sin(pp), np.cos(tt)], -1).reshape(-1, 3)
    w = (np.sin(tt) * np.cos(tt)).ravel() * (np.pi / 2 / nt) * (2 * np.pi / nphi)
    mu = np.cos(np.radians(theta_deg))
    src = np.repeat(H._sources([mu]), len(d), axis=0)
    return w @ top.eval(d, src, wavelengths=WAVES, lobes=Lobe.REFLECTION) / mu


def rule_top(top, theta_deg: float, nodes=H.TOP_NODES) -> np.ndarray:
    mu = np.cos(np.radians([theta_deg]))
    d, w = H.top_nodes(mu, top.alpha, top.distribution, *nodes)
    src = np.repeat(H._sources(mu), d.shape[1], axis=0)
    return w[0] @ top.eval(d[0], src, wavelengths=WAVES, lobes=Lobe.REFLECTION) / mu[0]


@pytest.mark.parametrize("alpha,distribution", [(0.12, "ggx"), (0.3, "beckmann"), (1.0, "ggx"), (0.05, "beckmann")])
def test_top_part_matches_a_brute_grid(alpha, distribution):
    m, _ = model(roughness=alpha)
    top = from_dict({**m.exact_part.to_dict(), "distribution": distribution})
    for theta in (8.0, 60.0):
        got, ref = rule_top(top, theta), brute_top(top, theta)
        assert np.all(np.abs(got - ref) < 1e-5), (theta, got, ref)


def test_narrow_lobe_converges():
    """alpha 1e-3 (the solver's smallest): the brute grid cannot resolve it, the rule at 4x
    its nodes can; and it tends to the smooth interface's Fresnel reflectance (its delta)."""
    m, d = model(roughness=1e-3)
    for theta in (8.0, 60.0):
        got = rule_top(m.exact_part, theta)
        dense = rule_top(m.exact_part, theta, (64, 48))
        assert np.all(np.abs(got - dense) < 1e-5), (got, dense)
        top = {k: v for k, v in d["interfaces"][0].items() if k not in ("alpha", "distribution")}
        smooth = from_dict({**d, "interfaces": [{**top, "type": "dielectric"}]})
        s = np.radians(theta)
        fresnel = smooth.delta_reflectance(np.array([[np.sin(s), 0.0, np.cos(s)]]), wavelengths=WAVES)[0]
        assert np.all(np.abs(got - fresnel) < 1e-4), (got, fresnel)


def test_total_matches_the_models_own_monte_carlo():
    m, _ = model()
    sol = solve(m, wavelengths=WAVES)
    thetas = np.array([8.0, 60.0])
    got = H.directional_albedo(sol, np.cos(np.radians(thetas)), WAVES)
    dense = H.directional_albedo(sol, np.cos(np.radians(thetas)), WAVES, scatter=(96, 48), top=(64, 48))
    assert np.all(np.abs(got - dense) < 1e-5), got - dense
    n = 1_000_000
    for theta, r in zip(thetas, got):
        s = np.radians(theta)
        wi = np.tile([np.sin(s), 0.0, np.cos(s)], (n, 1))
        smp = m.sample(wi, seed=5, wavelengths=WAVES)
        w = smp.weight * (smp.wo[:, 2:3] > 0)
        z = (r - w.mean(axis=0)) / (w.std(axis=0) / np.sqrt(n))
        assert np.all(np.abs(z) < Z), (theta, r, w.mean(axis=0), z)


STRUCTURE = """
[model]
kind = "full"
[structure]
exterior = "air"
substrate = "keratin"
[[structure.layers]]
name = "film"
material = "guanine"
thickness_nm = 400.0
[structure.interface]
roughness = 0.12
[structure.slab]
thickness_um = 4.0
sigma_a = "eumelanin"
pigment_absorption = 0.4
sigma_s = 0.4
hg_g = 0.6
[structure.base]
albedo = 0.35
[parameters]
roughness = { prior = "lognormal", median = 0.1, sigma = 0.2 }
"""


def rows(geometry, angle, out, wl, phi=None):
    n = len(angle)
    g = np.array([GEOMETRIES.index(x) for x in geometry])
    return Dataset(
        g,
        np.asarray(angle, float),
        np.asarray(out, float),
        np.asarray(wl, float),
        np.zeros(n),
        np.ones(n),
        phi_deg=None if phi is None else np.asarray(phi, float),
    )


def test_structure_forward_gives_totals_beside_brdf_rows():
    import tomllib

    config = FullStackConfig.parse(tomllib.loads(STRUCTURE))
    ds = rows(
        ["total", "brdf", "total", "total"],
        [8, 30, 8, 60],
        [np.nan, 30, np.nan, np.nan],
        [450, 550, 550, 650],
        [np.nan, 0, np.nan, np.nan],
    )
    names = [p.name for p in config.structure.parameters()]
    domains = {p.name: p for p in config.structure.parameters()}
    fwd = StructureSolverForward(ds, config.structure, names, domains)
    vec = np.array([p.default for p in config.structure.parameters()])
    got = fwd.evaluate(vec)
    sol = solve(from_dict(fwd.model_dict(vec)), wavelengths=WAVES)
    r = H.directional_albedo(sol, np.cos(np.radians([8.0, 60.0])), WAVES)
    assert np.allclose(got[[0, 2, 3]], [r[0, 0], r[0, 1], r[1, 2]], rtol=0, atol=1e-9), (got, r)
    src = H._sources(np.cos(np.radians([30.0])))
    det = np.array([[0.5, 0.0, np.sqrt(0.75)]])
    assert np.isclose(got[1], np.pi * sol.eval(det, src)[0, 1] / src[0, 2], rtol=0, atol=1e-9)
    with pytest.raises(ValueError, match="specular"):
        StructureSolverForward(rows(["specular"], [8], [np.nan], [550]), config.structure, names, domains)


def test_instrument_terms_act_on_the_incidence():
    """On total rows a sample tilt moves the incidence (8 -> 9.5 deg: R of the tilted source,
    rtol 1e-9, the same solution) and an illumination cone of 4 deg averages R over its
    directions (against a 12 x 48 rule in cos b x psi around the source; the forward model's
    4 x 12 rule: measured 2.0e-6 relative at 60 deg; rtol 1e-5, an absolute 2e-6, far below a
    sphere's noise)."""
    import tomllib
    from scipy.spatial.transform import Rotation

    config = FullStackConfig.parse(tomllib.loads(STRUCTURE))
    base = [p.name for p in config.structure.parameters()]
    names = [*base, "off", "acc"]
    domains = {p.name: p for p in config.structure.parameters()}
    ds = rows(["total", "total"], [8, 60], [np.nan, np.nan], [550, 550])
    terms = {"angle_offset_deg": "off", "acceptance_deg": "acc"}
    fwd = StructureSolverForward(ds, config.structure, names, domains, instruments=[(0, 2, terms)], on=set(terms))
    vec = np.array([p.default for p in config.structure.parameters()] + [0.0, 0.0])
    sol = solve(from_dict(fwd.model_dict(vec)), wavelengths=[550.0])

    def albedo(mu):
        return H.directional_albedo(sol, mu, [550.0])[:, 0]

    tilted = fwd.evaluate(np.append(vec[:-2], [1.5, 0.0]))
    assert np.allclose(tilted, albedo(np.cos(np.radians([9.5, 61.5]))), rtol=1e-9, atol=0)
    got = fwd.evaluate(np.append(vec[:-2], [0.0, 4.0]))
    x, w = np.polynomial.legendre.leggauss(12)
    ca = np.cos(np.radians(4.0))
    cb = ca + (1 - ca) * (x + 1) / 2
    psi = 2 * np.pi * (np.arange(48) + 0.5) / 48
    sb = np.sqrt(1 - cb**2)
    local = np.stack([np.outer(sb, np.cos(psi)).ravel(), np.outer(sb, np.sin(psi)).ravel(), np.repeat(cb, 48)], -1)
    weights = np.repeat(w, 48) / np.sum(np.repeat(w, 48))
    for row, theta in enumerate((8.0, 60.0)):
        s = H._sources(np.cos(np.radians([theta])))
        r, _ = Rotation.align_vectors(s, [[0.0, 0.0, 1.0]])
        want = weights @ albedo(r.apply(local)[:, 2])
        assert np.isclose(got[row], want, rtol=1e-5, atol=0), (got[row], want)
    assert abs(got[1] / albedo(np.cos(np.radians([60.0])))[0] - 1) > 1e-4  # the cone matters


def test_snake_full_model_gives_totals():
    """The snake's full model (bsdflab.fit.full_forward) reads total rows too: the rule on its
    own solution, beside a brdf row's pi f (the same solve)."""
    from bsdflab.fit.config import ModelSettings
    from bsdflab.fit.full_forward import SolverForwardModel
    from bsdflab.fit.parameters import ALL

    ds = rows(["total", "brdf"], [8, 30], [np.nan, 30], [550, 550], [np.nan, 0])
    fwd = SolverForwardModel(ds, ModelSettings(kind="full"))
    v = np.array([p.default for p in ALL.values()])
    got = fwd.evaluate(v)
    sol = solve(fwd.layered(v), wavelengths=[550.0])
    want = H.directional_albedo(sol, np.cos(np.radians([8.0])), [550.0])[0, 0]
    assert np.isclose(got[0], want, rtol=0, atol=1e-9), (got, want)
    assert 0.0 < got[0] < 1.0
    with pytest.raises(ValueError, match="row 1: a total row's angle_deg must be at most 85"):
        SolverForwardModel(rows(["total", "total"], [8, 88], [np.nan] * 2, [550] * 2), ModelSettings(kind="full"))
