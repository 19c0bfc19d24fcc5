"""Whether a PFMC table's thickness axis was tabulated with the film rule of estimator
versions before 8: every boundary's film rescaled to the node's thickness, not the top's
alone. The cells of such a file describe another stack than its model (a filmed base or
interior interface rescaled), while the lookup's delta lobes and the base's exact part
follow the model as version 8 does; ``TableBSDF`` warns when it reads one."""

from __future__ import annotations

from typing import Any

from bsdflab.bsdfs.base import from_dict

FIRST_TOP_ONLY_VERSION = 8  # core/include/bsdflab/estimate.h: a query's film is the top's alone


def old_film_axis(table) -> str | None:
    """Why ``table``'s cells rescale films below the top (a message), or None: a PFMC table
    of an estimator version before 8 with a thickness axis and a film below the top.
    Adding-doubling tables always gave the node to the top alone; a table of unknown version
    is not judged."""
    meta: dict[str, Any] = table.meta
    version = meta.get("estimator_version")
    if meta.get("method") == "adding-doubling" or not table.grid.thickness_nm:
        return None
    if isinstance(version, bool) or not isinstance(version, int) or version >= FIRST_TOP_ONLY_VERSION:
        return None
    try:
        model = from_dict(table.model)
    except (ValueError, TypeError):
        return None
    below = [*getattr(model, "interfaces", ())[1:], getattr(model, "base", None)]
    if not any(getattr(m, "film", None) for m in below if m is not None):
        return None
    return (
        f"this table was made by estimator version {version}, which gave each thickness node's film to "
        "every boundary: its cells rescale the films below the top, unlike its model and its delta "
        f"lobes (version {FIRST_TOP_ONLY_VERSION} gives the node to the top alone); tabulate it again"
    )
