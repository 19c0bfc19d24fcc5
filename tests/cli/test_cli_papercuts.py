"""Papercuts a new user met (issue 34), each as the user meets it: through the CLI.

Each test names the mutation it catches: restoring the old behaviour fails it."""
import re
from pathlib import Path

import numpy as np
import pytest

from bsdflab.cli.main import build_parser
from support.cli import cli, one_line_error

ROOT = Path(__file__).resolve().parents[2]


def test_render_list_needs_no_scene():
    """Mutation: `scene` positional required again -> exit 2 from argparse."""
    r = cli("render", "--list")
    assert r.returncode == 0, r.stderr
    assert re.search(r"^snake\s", r.stdout, re.M) and re.search(r"^sphere\s", r.stdout, re.M)


def test_render_without_a_scene_says_how_to_list_them():
    """Mutation: dropping the check -> a traceback on `None.endswith`, not a one-line error."""
    one_line_error(cli("render"), "name a scene", "--list")


def test_validate_list_needs_no_out():
    """Mutation: `--out` required again -> exit 2 from argparse."""
    r = cli("validate", "--list")
    assert r.returncode == 0, r.stderr
    assert "basic/chi2/diffuse" in r.stdout


def test_validate_without_out_names_it():
    """Mutation: dropping the check -> validate(None, ...) fails somewhere inside."""
    one_line_error(cli("validate", "--only", "basic/chi2/diffuse"), "--out is required")


def test_export_help_prints_one_percent_sign():
    """Mutation: the description's '%%' (argparse formats help strings, not descriptions)."""
    r = cli("export", "--help")
    assert r.returncode == 0, r.stderr
    text = " ".join(r.stdout.split())
    assert "±15 % film-thickness spread" in text and "%%" not in text


def test_usage_lists_every_command():
    """docs/usage.md's command list names every subcommand the parser has, and no other.
    Mutation: the list without `export` (as it was)."""
    parser = build_parser()
    commands = set(next(a for a in parser._actions if a.dest == "command").choices)
    text = (ROOT / "docs" / "usage.md").read_text()
    listed = re.search(r"lists the commands \(([^;]*);", text, re.S)
    assert listed, "docs/usage.md: the sentence listing the commands is gone"
    assert set(re.findall(r"`(\w+)`", listed.group(1))) == commands


def test_bad_preset_override_names_the_valid_keys():
    """Mutation: calling the preset with the bad keyword -> Python's 'unexpected keyword
    argument', which names neither the valid keys nor the right one."""
    r = cli("export", "--preset", "xenopeltis", "--set", "film_thickness=450", "--format", "gltf",
            "--out", "/nonexistent-dir-for-bsdflab-test/x.gltf")
    one_line_error(r, "'film_thickness'", "film_thickness_nm", "roughness", "base_albedo")
    assert "unexpected keyword" not in r.stderr


def test_stack_export_error_names_substitute(tmp_path):
    """Mutation: the old message ('ask for the best single-film substitute') names no flag."""
    r = cli("export", "--preset", "xenopeltis-stack", "--format", "gltf", "--out", str(tmp_path / "s.gltf"))
    one_line_error(r, "film stack", "--substitute")
    assert list(tmp_path.iterdir()) == []


def _fit_commands(page: Path) -> list[str]:
    blocks = re.findall(r"```(?:sh|bash)\n(.*?)```", page.read_text(), re.S)
    return [line for b in blocks for line in b.splitlines() if line.startswith("bsdflab fit")]


@pytest.mark.parametrize("page", ["fit.md", "usage.md"])
def test_fit_examples_write_outside_the_repository(page, tmp_path):
    """Every `--out` of the `bsdflab fit` examples is an absolute path outside the checkout,
    and the simulate example runs as written (its folder moved into tmp_path).
    Mutation: the old `--out examples/fit/data.csv` (it overwrote the shipped data)."""
    commands = _fit_commands(ROOT / "docs" / page)
    assert len(commands) >= 2
    for line in commands:
        out = re.search(r"--out\s+(\S+)", line).group(1)
        assert out.startswith("/") and not Path(out).resolve().is_relative_to(ROOT), (page, line)
    simulate = next(line for line in commands if line.startswith("bsdflab fit simulate"))
    args = simulate.split("#")[0].split()[1:]
    out = args[args.index("--out") + 1]
    args[args.index("--out") + 1] = str(tmp_path / Path(out).name)
    args = [str(ROOT / a) if a.startswith("examples/") else a for a in args]
    r = cli(*args)
    assert r.returncode == 0, r.stderr
    assert (tmp_path / Path(out).name).read_text().count("\n") > 100


def test_lobe_plot_shows_the_body_lobe_and_keeps_its_legend_outside():
    """The snake's body lobe (100-1000x below its gloss peak) keeps a visible radius, and
    the legend covers no part of the polar axes. Mutations: a linear radius (log_radius
    returning its input: the body lobe's radius falls to ~1e-3 of the peak's); the legend
    back at loc="lower left" inside the axes."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from bsdflab.plots.lobe import lobe_panel
    from bsdflab.presets import xenopeltis

    fig = plt.figure(figsize=(5, 4.6), constrained_layout=True)
    ax = fig.add_subplot(1, 1, 1, projection="polar")
    theta_i = np.radians(30)
    wi = np.array([-np.sin(theta_i), 0.0, np.cos(theta_i)])
    lobe_panel(ax, xenopeltis(samples=64), wi, samples=2000)
    green = next(line for line in ax.get_lines() if line.get_label() == "G")
    t, r = green.get_xdata(), green.get_ydata()
    body = r[np.argmin(np.abs(t - np.radians(-60)))]  # back toward the light, far from the gloss
    assert body > 0.15 * r.max(), (body, r.max())
    fig.canvas.draw()
    legend = ax.get_legend().get_window_extent()
    assert not legend.overlaps(ax.get_window_extent())
    plt.close(fig)
