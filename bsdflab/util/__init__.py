"""The bottom layer: argument checks (``args``), progress and cancel of C++ jobs
(``progress``), work-unit runners (``runners``), registries with lazy entries
(``registry``), optional dependencies (``extras``), atomic files (``files``), resource caps
(``limits``) and native-output silencing (``native_output``). Modules here import nothing
from the rest of bsdflab."""
