"""A reference study whose figures nothing looks at: the tests that compare a job's summary
with ``run_study`` / ``run_stack_study`` in this process read only the summary, so the
reference's plot calls are made no-ops. The plots draw no random numbers (the study's rng
goes to the predictive draws before and after them), so the summary is the same to the bit;
the job's own study keeps every figure."""
from __future__ import annotations

import contextlib

# the figures of bsdflab.fit.study and bsdflab.fit.stack_study that feed nothing back
PLOTS = ("corner_plot", "predictive_plot", "residual_plot", "trace_plot")
MODULES = ("bsdflab.fit.study", "bsdflab.fit.stack_study")


def _none(*args, **kwargs) -> None:
    return None


@contextlib.contextmanager
def no_figures(monkeypatch):
    """Within the block, the study writers draw no figures (a thread-executor job running
    meanwhile would draw none either: call it once the job is done)."""
    with monkeypatch.context() as m:
        for module in MODULES:
            for name in PLOTS:
                m.setattr(f"{module}.{name}", _none)
        yield
