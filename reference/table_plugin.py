"""Mitsuba 3 BSDF plugin ``bsdflab_table``: a bsdflab table BSDF inside Mitsuba's renders.

    mi.load_dict(plugin_dict("/path/table.exr"))       # a table file
    mi.load_dict(plugin_dict(table_bsdf))              # an in-memory TableBSDF (or any BSDF)

The plugin hands Mitsuba's queries to ``bsdflab.tables.TableBSDF`` (the same C++ lookup
our renderer uses), so an image rendered by Mitsuba through it tests our renderer's light
transport, not the table. Any other bsdflab BSDF object works the same way (same
vectorised eval / pdf / sample); objects travel to the plugin through a registry here,
since Mitsuba's properties hold only strings, numbers and Mitsuba objects. Both codes share the conventions the plugin
relies on: local frame with +z the shading normal, wi and wo pointing away, eval = f |cos theta_o|,
sample weight = f |cos theta_o| / pdf, a delta lobe's pdf = the probability of picking it.

How Python sees the queries: in ``llvm_ad_rgb`` Mitsuba traces its path loop and BSDF
calls symbolically, so a Python method would see placeholders that ``.numpy()`` cannot
read. Rendering inside ``wavefront_mode()`` switches Dr.Jit to evaluated loops and calls:
every bounce is a kernel launch, and each plugin method runs once per bounce on concrete
arrays of all the lanes that hit the table material. In ``scalar_rgb`` each method runs
once per query (slow, but needs no flags).
"""
from __future__ import annotations

import contextlib
import os

import numpy as np

from bsdflab.bsdfs.base import BSDF
from bsdflab.lobes import Lobe
from bsdflab.reference.mitsuba_env import mitsuba

PLUGIN_NAME = "bsdflab_table"

# The flags that make Python see concrete arrays (drjit 1.x names).
_EVALUATED_FLAGS = ("SymbolicLoops", "SymbolicCalls", "SymbolicConditionals")

_objects: dict[str, BSDF] = {}
_classes: dict[str, type] = {}


def _lobe_pairs(mi):
    """(bsdflab Lobe bit, Mitsuba BSDFFlags bit) for every lobe kind."""
    F = mi.BSDFFlags
    return ((Lobe.DIFFUSE_REFLECTION, F.DiffuseReflection),
            (Lobe.GLOSSY_REFLECTION, F.GlossyReflection),
            (Lobe.DELTA_REFLECTION, F.DeltaReflection),
            (Lobe.DIFFUSE_TRANSMISSION, F.DiffuseTransmission),
            (Lobe.GLOSSY_TRANSMISSION, F.GlossyTransmission),
            (Lobe.DELTA_TRANSMISSION, F.DeltaTransmission))


def plugin_dict(table) -> dict:
    """The ``mi.load_dict`` entry of a table file (str or path) or of a bsdflab BSDF
    object; registers the plugin first."""
    register()
    if isinstance(table, BSDF):
        key = f"bsdf-{id(table)}"
        _objects[key] = table  # kept alive: a scene may be loaded from the dict later
        return {"type": PLUGIN_NAME, "object": key}
    return {"type": PLUGIN_NAME, "filename": os.fspath(table)}


@contextlib.contextmanager
def wavefront_mode():
    """Evaluated (not symbolic) loops, calls and conditionals for the duration: needed while
    ``mi.render`` runs a scene with the plugin in a JIT variant. Restores the flags after."""
    import drjit as dr

    with contextlib.ExitStack() as stack:
        for name in _EVALUATED_FLAGS:
            stack.enter_context(dr.scoped_set_flag(getattr(dr.JitFlag, name), False))
        yield


def register() -> str:
    """Register the plugin with Mitsuba's active reference variant (once per variant)."""
    mi = mitsuba()
    if mi.variant() not in _classes:
        cls = _classes[mi.variant()] = _make_plugin_class(mi)
        mi.register_bsdf(PLUGIN_NAME, lambda props: cls(props))
    return PLUGIN_NAME


def scene_uses_plugin(mi_scene) -> bool:
    """True when a loaded Mitsuba scene has a shape whose BSDF is this plugin (rendering it
    in a JIT variant then needs ``wavefront_mode()``)."""
    plugin_classes = tuple(_classes.values())
    return bool(plugin_classes) and any(isinstance(s.bsdf(), plugin_classes) for s in mi_scene.shapes())


def _make_plugin_class(mi):
    """The mi.BSDF subclass for the variant that ``mi`` has active now."""
    import drjit as dr

    pairs = _lobe_pairs(mi)
    jit = dr.is_jit_v(mi.Float)

    def to_numpy(value, n: int, columns: int | None) -> np.ndarray:
        """A Mitsuba array (or scalar) as float64 numpy: (n, columns), or (n,) for None."""
        a = np.asarray(value, dtype=np.float64)
        if columns is None:
            return np.broadcast_to(a.reshape(-1), (n,)).copy()
        a = a.reshape(columns, -1).T if jit else a.reshape(1, columns)
        return np.broadcast_to(a, (n, columns)).copy()

    def to_mitsuba(kind, a: np.ndarray):
        a = np.asarray(a)
        if not jit:
            return kind(*a[0]) if a.ndim == 2 else kind(a[0])
        return kind(np.ascontiguousarray(a.T if a.ndim == 2 else a))

    def lobes_to_flags(lobes: np.ndarray) -> np.ndarray:
        out = np.zeros(lobes.shape, dtype=np.uint32)
        for ours, theirs in pairs:
            out[(lobes & int(ours)) != 0] |= np.uint32(int(theirs))
        return out

    class TablePlugin(mi.BSDF):
        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            from bsdflab.tables import TableBSDF

            if "object" in props:
                self.source = str(props["object"])
                if self.source not in _objects:
                    raise ValueError(f"{PLUGIN_NAME}: no registered BSDF {self.source!r}")
                self.table = _objects[self.source]
            else:
                self.source = str(props["filename"])
                self.table = TableBSDF(path=self.source)
            lobes = int(self.table.lobes)
            self.components = [(ours, theirs) for ours, theirs in pairs if lobes & int(ours)]
            flags = 0
            for _, theirs in self.components:
                flags |= int(theirs)
            self.m_flags = flags
            self.m_components = [int(theirs) for _, theirs in self.components]

        # -- Mitsuba's context -> bsdflab's lobe mask -------------------------------
        def _lobes(self, ctx) -> int:
            mask = 0
            for i, (ours, theirs) in enumerate(self.components):
                wanted = ctx.component in (i, 0xFFFFFFFF)
                if wanted and (int(ctx.type_mask) & int(theirs)):
                    mask |= int(ours)
            return mask

        def _width(self, *values) -> int:
            return max(dr.width(v) for v in values) if jit else 1

        def _directions(self, si, wo, active):
            n = self._width(si.wi, wo, active)
            live = to_numpy(active, n, None) > 0
            return n, live, to_numpy(si.wi, n, 3), to_numpy(wo, n, 3)

        def _eval_pdf_numpy(self, ctx, si, wo, active):
            n, live, wi, wo_np = self._directions(si, wo, active)
            value, pdf = np.zeros((n, 3)), np.zeros(n)
            lobes = self._lobes(ctx)
            if lobes and live.any():
                value[live] = self.table.eval(wi[live], wo_np[live], lobes=lobes)
                pdf[live] = self.table.pdf(wi[live], wo_np[live], lobes=lobes)
            return value, pdf

        def eval(self, ctx, si, wo, active=True):
            value, _ = self._eval_pdf_numpy(ctx, si, wo, active)
            return to_mitsuba(mi.Color3f, value)

        def pdf(self, ctx, si, wo, active=True):
            _, pdf = self._eval_pdf_numpy(ctx, si, wo, active)
            return to_mitsuba(mi.Float, pdf)

        def eval_pdf(self, ctx, si, wo, active=True):
            value, pdf = self._eval_pdf_numpy(ctx, si, wo, active)
            return to_mitsuba(mi.Color3f, value), to_mitsuba(mi.Float, pdf)

        def sample(self, ctx, si, sample1, sample2, active=True):
            n = self._width(si.wi, sample1, sample2, active)
            live = to_numpy(active, n, None) > 0
            wi = to_numpy(si.wi, n, 3)
            u1, u2 = to_numpy(sample1, n, None), to_numpy(sample2, n, 2)
            wo, weight = np.zeros((n, 3)), np.zeros((n, 3))
            pdf, eta, lobe = np.zeros(n), np.ones(n), np.zeros(n, dtype=np.int64)
            lobes = self._lobes(ctx)
            if lobes and live.any():
                # bsdflab wants uniforms in [0, 1); float32 samples can round up to 1.
                s = self.table.sample(wi[live], np.minimum(u1[live], 1 - 1e-12),
                                      np.minimum(u2[live], 1 - 1e-12), lobes=lobes)
                ok = s.lobe != 0
                idx = np.flatnonzero(live)[ok]
                wo[idx], weight[idx], pdf[idx] = s.wo[ok], s.weight[ok], s.pdf[ok]
                eta[idx], lobe[idx] = s.eta[ok], s.lobe[ok]
            flags = lobes_to_flags(lobe)
            component = np.zeros(n, dtype=np.uint32)
            for i, (ours, _) in enumerate(self.components):
                component[(lobe & int(ours)) != 0] = i
            bs = dr.zeros(mi.BSDFSample3f, n) if jit else mi.BSDFSample3f()
            bs.wo = to_mitsuba(mi.Vector3f, wo)
            bs.pdf = to_mitsuba(mi.Float, pdf)
            bs.eta = to_mitsuba(mi.Float, eta)
            bs.sampled_type = to_mitsuba(mi.UInt32, flags)
            bs.sampled_component = to_mitsuba(mi.UInt32, component)
            return bs, to_mitsuba(mi.Color3f, weight)

        def traverse(self, callback):
            """Exposes no parameters: the table is fixed data, neither differentiable nor
            editable through mi.traverse."""

        def to_string(self):
            return f"TablePlugin[source={self.source!r}, flags={self.m_flags}]"

    return TablePlugin
