"""Time to solution on W workers, from figures measured on this machine.

The model (Amdahl's law plus per-unit overhead and result transfer):

    T(W) = T_serial + waves(W) * (u * t_item + t_unit + u * b_item / B)
    waves(W) = ceil(N / u / W)                       (N items in units of u items)

- ``t_item``: compute time of one item (a table cell, a pixel-sample) on one worker, measured;
- ``t_unit``: fixed cost per unit (scheduling, (de)serialisation, a round trip), measured
  as the time of a unit minus its compute time;
- ``b_item / B``: bytes returned per item over the driver's bandwidth;
- ``T_serial``: the driver's own work (resolving inputs, assembling, writing), measured.

``waves`` makes the load-balance tail explicit: with fewer units than a multiple of W the
last wave leaves workers idle. ``recommend_unit`` picks the largest unit that still gives
every worker ``min_waves`` waves (balance under heterogenous speed) and keeps the overhead
below ``max_overhead`` of the compute. bench/bench_distributed.py measures the inputs and
prints this model for the spectral fine-grid table; docs/distributed.md has the numbers.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass


@dataclass(frozen=True)
class CostInputs:
    items: int              # N: cells (tabulation) or samples (rendering)
    t_item_s: float         # compute per item on one worker
    t_unit_s: float         # fixed overhead per unit
    bytes_per_item: float   # result bytes per item
    bandwidth_Bps: float    # driver's network bandwidth
    t_serial_s: float       # driver-side serial part

    def as_dict(self) -> dict:
        return asdict(self)


def time_to_solution(c: CostInputs, workers: int, unit_items: int) -> float:
    if workers < 1 or unit_items < 1:
        raise ValueError("workers and unit_items must be >= 1")
    units = math.ceil(c.items / unit_items)
    waves = math.ceil(units / workers)
    per_unit = unit_items * c.t_item_s + c.t_unit_s + unit_items * c.bytes_per_item / c.bandwidth_Bps
    return c.t_serial_s + waves * per_unit


def recommend_unit(c: CostInputs, workers: int, max_overhead: float = 0.02, min_waves: int = 4) -> int:
    """Items per unit: overhead ≤ max_overhead of compute where possible, and at least
    ``min_waves`` units per worker; ties broken by the model's time."""
    smallest = max(1, math.ceil(c.t_unit_s / (max_overhead * c.t_item_s)))
    largest = max(1, c.items // (workers * min_waves))
    if smallest <= largest:
        candidates = {smallest, largest, int(math.sqrt(smallest * largest))}
        return min(candidates, key=lambda u: (time_to_solution(c, workers, u), -u))
    return largest  # too few items for both goals: keep the workers busy


def scaling_table(c: CostInputs, workers=(1, 16, 64, 256)) -> list[dict]:
    rows = []
    t1 = time_to_solution(c, 1, recommend_unit(c, 1))
    for w in workers:
        u = recommend_unit(c, w)
        t = time_to_solution(c, w, u)
        rows.append({"workers": w, "unit_items": u, "units": math.ceil(c.items / u), "seconds": t,
                     "speedup": t1 / t, "efficiency": t1 / t / w})
    return rows
