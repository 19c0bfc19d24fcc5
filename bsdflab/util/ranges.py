"""The physical ranges of the library's inputs, written once (docs/limits.md): the Python
checks (`bsdflab.util.args`) and the service's routers read them from here, so a value the
library accepts the service accepts too."""

from __future__ import annotations

# Refractive indices (the real part n, and a conductor's eta) from 1e-3 to 1e3 cover every
# optical material, metals' n < 1 and metamaterials included; beyond them the Fresnel and
# Snell arithmetic loses all precision (n = 1e-200 samples NaN directions, 1e200 overflows
# the microfacet terms). Extinction k is bounded the same way; two indices in range have a
# ratio within [1e-6, 1e6].
MIN_IOR, MAX_IOR = 1e-3, 1e3
MAX_EXTINCTION = 1e3
# Wavelengths from 1 nm (soft X-ray; shorter ones -- denormals gave NaN -- break the
# phase arithmetic) to 1e12 nm: long wavelengths only make phases vanish, and the
# scaled-stack identity of plots/film_colour evaluates at lambda / s up to ~1e12 nm.
MIN_WAVELENGTH_NM, MAX_WAVELENGTH_NM = 1.0, 1e12
# Film thicknesses: 0 to 1 m (an opaque absorbing layer may be thick; phases 2 pi n d / lambda
# stay below 1e13 rad, finite in double precision; 1e308 gave NaN).
MAX_FILM_THICKNESS_NM = 1e9

# The same as (lo, hi) pairs, for check.real_scalar(name, value, *RANGE).
IOR_RANGE = (MIN_IOR, MAX_IOR)
EXTINCTION_RANGE = (0.0, MAX_EXTINCTION)
WAVELENGTH_RANGE_NM = (MIN_WAVELENGTH_NM, MAX_WAVELENGTH_NM)
FILM_THICKNESS_RANGE_NM = (0.0, MAX_FILM_THICKNESS_NM)
