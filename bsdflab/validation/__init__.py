"""bsdflab.validation: the registry of checks that the tests parametrise over and that
`bsdflab validate` renders as a report (docs/validation.md).

>>> from bsdflab.validation import REGISTRY, load_checks, run_check
>>> load_checks()
>>> result = run_check(REGISTRY["basic/chi2/diffuse"], "quick")   # doctest: +SKIP
"""
from bsdflab.validation.registry import FAMILIES, LEVELS, REGISTRY, Check, Context, Figure, Outcome, Registry, effort
from bsdflab.validation.report import SCHEMA_PATH, load_checks, validate
from bsdflab.validation.runner import CheckResult, run_check, run_checks

__all__ = ["FAMILIES", "LEVELS", "REGISTRY", "SCHEMA_PATH", "Check", "CheckResult", "Context", "Figure",
           "Outcome", "Registry", "effort", "load_checks", "run_check", "run_checks", "validate"]
