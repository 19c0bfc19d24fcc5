"""The docs point at real files.

Every reference a reader might follow in ``docs/*.md`` and ``README.md`` must resolve in
today's tree, so that a moved or deleted file breaks this test instead of the docs going
stale silently. Checked:

- a backticked repository path (``bsdflab/...``, ``core/...``, ``service/...``,
  ``tests/...``, ``bench/...``, ``docs/...``, ``examples/...``, ``reference/...``) exists;
  a glob (``*``) matches at least one file; ``::name`` after a test file names a function
  or class defined in it;
- a ``file.ext:NNN`` reference (backticked or not) names an existing file, and NNN (or
  each end of NNN-MMM) is a line of it;
- a ``::test_07`` member may be the numbered prefix of the test's name;
- a backticked bare source file name (``thin_film.h``, ``stages.py``) is some file of the
  tree;
- a backticked dotted name under ``bsdflab.`` imports (longest importable module, then
  attributes);
- a relative Markdown link ``[text](file.md)`` names an existing file.

Power: ``test_the_checker_catches_bad_references`` runs the same checker over a page with
one deliberately wrong reference of each kind and requires every one to be reported.
"""
from __future__ import annotations

import importlib
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PAGES = sorted((ROOT / "docs").glob("*.md")) + [ROOT / "README.md"]
TOP_FOLDERS = ("bsdflab", "core", "service", "tests", "bench", "docs", "examples", "reference")
SOURCE_EXT = ("py", "h", "cpp")

BACKTICKED = re.compile(r"`([^`\n]+)`")
REPO_PATH = re.compile(r"^(?:\./)?((?:" + "|".join(TOP_FOLDERS) + r")/[\w./*\-{},]*)(::[\w\[\]\-]+)?$")
LINE_REF = re.compile(r"(?<![\w/.])((?:[\w\-]+/)*[\w\-]+\.(?:py|h|cpp|md|toml)):(\d+)(?:-(\d+))?\b")
BARE_FILE = re.compile(r"^[\w\-]+\.(?:" + "|".join(SOURCE_EXT) + r")$")
DOTTED = re.compile(r"^(bsdflab(?:\.\w+)+)(?:\(.*\))?$")
MD_LINK = re.compile(r"\]\(([^)\s#]*[./][^)\s#]*)(?:#[^)]*)?\)")
# the table format's EXR header attributes are namespaced `bsdflab.*` but are not modules
NOT_MODULE_NAMES = {"table_format.md"}


def _tree_files() -> dict[str, list[Path]]:
    """Basename -> files of the repository (tracked sources, not build products)."""
    skip = {".git", ".venv", ".venv-blender", "build", ".cache", "node_modules", "__pycache__"}
    names: dict[str, list[Path]] = {}
    stack = [ROOT]
    while stack:
        folder = stack.pop()
        for entry in folder.iterdir():
            if entry.is_dir():
                if entry.name not in skip and not entry.name.startswith(".pytest"):
                    stack.append(entry)
            else:
                names.setdefault(entry.name, []).append(entry)
    return names


def _resolve_dotted(name: str) -> bool:
    parts = name.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except ImportError:
            continue
        for attr in parts[cut:]:
            if not hasattr(obj, attr):
                return False
            obj = getattr(obj, attr)
        return True
    return False


def _line_count(path: Path) -> int:
    return len(path.read_text(encoding="utf-8", errors="replace").splitlines())


def _find_line_target(name: str, files: dict[str, list[Path]], page: Path) -> list[Path]:
    for base in (ROOT, page.parent):
        if (base / name).is_file():
            return [base / name]
    if "/" not in name:
        return files.get(name, [])
    return [p for p in files.get(Path(name).name, []) if p.as_posix().endswith("/" + name)]


def check_page(text: str, page: Path, files: dict[str, list[Path]]) -> list[str]:
    """Every broken reference of one page, as 'page:line: message'."""
    problems: list[str] = []
    for lineno, line in enumerate(text.splitlines(), 1):
        where = f"{page.name}:{lineno}"
        for match in LINE_REF.finditer(line):
            name, first, last = match.group(1), int(match.group(2)), match.group(3)
            targets = _find_line_target(name, files, page)
            if not targets:
                problems.append(f"{where}: `{match.group(0)}`: no file {name}")
                continue
            wanted = max(first, int(last or first))
            if not any(_line_count(t) >= wanted for t in targets):
                problems.append(f"{where}: `{match.group(0)}`: {name} has fewer than {wanted} lines")
        for match in BACKTICKED.finditer(line):
            token = match.group(1).strip().rstrip(".,;:")
            token = LINE_REF.sub(lambda m: m.group(1), token)
            repo = REPO_PATH.match(token)
            if repo:
                problems += _check_repo_path(repo.group(1), repo.group(2), where)
            elif BARE_FILE.match(token) and token not in files:
                problems.append(f"{where}: `{token}`: no file of that name in the repository")
            elif (
                page.name not in NOT_MODULE_NAMES
                and DOTTED.match(token)
                and not _resolve_dotted(DOTTED.match(token).group(1))
            ):
                problems.append(f"{where}: `{token}`: does not import")
        for match in MD_LINK.finditer(line):
            target = match.group(1)
            if "://" in target or target.startswith("mailto:"):
                continue
            if not (page.parent / target).exists():
                problems.append(f"{where}: link ({target}): no such file")
    return problems


def _check_repo_path(path: str, member: str | None, where: str) -> list[str]:
    # `bsdflab/validation/checks/<family>.py` style placeholders name a pattern, not a file
    if "<" in path or "{" in path:
        return []
    path = path.rstrip("/")
    if "*" in path:
        return [] if list(ROOT.glob(path)) else [f"{where}: `{path}`: the glob matches nothing"]
    target = ROOT / path
    if not target.exists():
        return [f"{where}: `{path}`: no such file or folder"]
    if member:
        name = member[2:].split("[")[0]
        source = target.read_text(encoding="utf-8")
        if not re.search(rf"^\s*(?:async\s+)?(?:def|class)\s+{re.escape(name)}(?:_\w*)?\b", source, re.M):
            return [f"{where}: `{path}{member}`: {name} is not defined there"]
    return []


@pytest.fixture(scope="module")
def files():
    return _tree_files()


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_every_reference_in_the_page_exists(page, files):
    problems = check_page(page.read_text(encoding="utf-8"), page, files)
    assert not problems, "stale references:\n" + "\n".join(problems)


def test_the_checker_catches_bad_references(files):
    """Mutation: each line below is one wrong reference of a kind the checker covers; each
    must be reported (and the good line must not be)."""
    page = ROOT / "docs" / "ARCHITECTURE.md"
    bad = "\n".join(
        [
            "`bsdflab/_validate.py` is gone",
            "`bsdflab/tables/nonexistent_*.py`",
            "see bsdflab/tables/cache.py:99999 for the key",
            "`tests/docs/test_docs_paths.py::test_no_such_test`",
            "`film_lookup_v2.h` reads films",
            "`bsdflab._jobs.monitored` cancels",
            "[missing](no_such_page.md)",
        ]
    )
    good = "`bsdflab/tables/cache.py` and `bsdflab.tables.tabulate` and [usage](usage.md) and `bsdflab/util/files.py:1`"
    problems = check_page(bad + "\n" + good, page, files)
    reported = {int(p.split(":")[1]) for p in problems}
    assert reported == set(range(1, 8)), problems
