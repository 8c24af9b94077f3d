"""The docs agree with the code where a machine can tell: the keyword tables of docs/python-settings.md
against the settings' defaults, the JSON fields of docs/cli.md against `sgdicp register --json`,
and the data paths that the README and `--help` name."""

from __future__ import annotations

import json
import re
import subprocess

import pytest

import sgd_icp
from conftest import REPO_ROOT, find_cli, shared_data_dir

DOCS = REPO_ROOT / "docs"


def keyword_tables(text: str):
    """(header, rows) of every markdown table whose header starts with `| keyword | sets`."""
    tables, rows, header = [], None, None
    for line in text.splitlines():
        if line.startswith("| keyword | sets"):
            header, rows = line, []
        elif rows is not None and line.startswith("|"):
            if not line.startswith("| ---"):
                rows.append([c.strip() for c in line.strip("|").split("|")])
        elif rows is not None:
            tables.append((header, rows))
            rows = None
    return tables


def resolve(obj, dotted: str):
    for part in dotted.split("."):
        obj = getattr(obj, part)
    return obj


def documented_matches(doc: str, value) -> bool:
    if isinstance(value, sgd_icp.Distance):
        value = value.value
    if isinstance(value, bool):
        return doc == f"`{value}`"
    if isinstance(value, (int, float)):
        return float(doc) == pytest.approx(float(value), rel=1e-9)
    name = getattr(value, "name", str(value)).replace("_", "-").lower()
    return doc.strip('`"').lower() == name


def test_python_md_keyword_defaults_are_the_settings_defaults():
    tables = keyword_tables((DOCS / "python-settings.md").read_text())
    assert len(tables) >= 2
    checked = 0
    for header, rows in tables:
        base = sgd_icp.BatchSettings() if "BatchSettings" in header else sgd_icp.Settings()
        for keyword, sets, default, *_ in rows:
            names = re.findall(r"`([a-z_.]+)`", sets)
            if "," in keyword or len(names) != 1 or not re.fullmatch(r"[\w.+-]+|`.*`", default):
                continue  # several keywords in one row, or a prose default
            try:
                value = resolve(base, names[0])
            except AttributeError:
                continue
            assert documented_matches(default, value), (
                f"docs/python-settings.md: {keyword} documents {default}, the code has {value!r}")
            checked += 1
    assert checked >= 25


def test_cli_md_json_fields_are_the_cli_output():
    cli = find_cli()
    if cli is None:
        pytest.skip("sgdicp executable not found")
    demo = REPO_ROOT / "data" / "demo"
    out = subprocess.run(
        [str(cli), "register", str(demo / "car_cloud401.csv"), str(demo / "car_cloud400.csv"),
         "--json", "--ground-truth", str(demo / "T_gt.txt")],
        capture_output=True, text=True, check=True, timeout=120)
    fields = set(json.loads(out.stdout))
    text = (DOCS / "cli.md").read_text()
    bullet = re.search(r"- `--json` prints one object:(.*?)\n- ", text, re.S).group(1)
    documented = set(re.findall(r"`([a-z_]+)`", bullet))
    assert documented == fields, (
        f"docs/cli.md --json: missing {sorted(fields - documented)}, "
        f"not printed {sorted(documented - fields)}")


def test_shared_data_paths_named_in_readme_and_help_exist():
    if not (shared_data_dir() / "PAIRS.md").is_file():
        pytest.skip("real data not found")
    texts = [(REPO_ROOT / "README.md").read_text()]
    cli = find_cli()
    if cli is not None:
        texts.append(subprocess.run([str(cli), "bench", "--help"], capture_output=True,
                                    text=True, timeout=60).stdout)
    paths = {m for t in texts for m in re.findall(r"\.\./shared/data/[\w./-]*\w", t)}
    assert paths
    for p in paths:
        if "*" not in p:
            assert (REPO_ROOT / p).exists(), f"{p} does not exist"


def test_readme_python_example_runs_as_written(monkeypatch):
    text = (REPO_ROOT / "README.md").read_text()
    section = text[text.index("## Python"):]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    monkeypatch.chdir(REPO_ROOT)
    namespace: dict = {}
    exec(compile(code, "README.md", "exec"), namespace)  # noqa: S102 - our own README
    assert namespace["r"].converged


@pytest.mark.parametrize("command, solvers", [("register", ("sgd",)), ("odometry", ("odometry",))])
def test_the_common_settings_are_the_ones_the_cli_help_shows(command, solvers):
    """The table marks the settings a user sets (common): Python lists them first, and the CLI's
    --help, which shows at most 15 options, shows every one of them."""
    cli = find_cli()
    if cli is None:
        pytest.skip("sgdicp executable not found")
    short = subprocess.run([str(cli), command, "--help"], capture_output=True, text=True,
                           check=True, timeout=60).stdout
    common = [k for solver in solvers for k, _, _, is_common in sgd_icp._core._settings_keywords(solver)
              if is_common]
    assert common
    for keyword in common:
        assert f"--{keyword.replace('_', '-')} " in short, f"{command} --help lacks {keyword}"


def test_readme_cli_lines_run_as_written(tmp_path):
    """Every line of the README's "Use" block runs: the demo pair for SOURCE and REFERENCE, three
    KITTI scans for the folders (the map of `odometry --map-out` localized in by `localize`)."""
    cli = find_cli()
    scans = sorted((shared_data_dir() / "kitti_odometry_seq00" / "velodyne").glob("*.bin"))[:3]
    if cli is None or len(scans) < 3:
        pytest.skip("sgdicp executable or the KITTI scans not found")
    folder = tmp_path / "frames"
    folder.mkdir()
    for scan in scans:
        (folder / scan.name).write_bytes(scan.read_bytes())
    text = (REPO_ROOT / "README.md").read_text()
    section = text[text.index("## Use"):]
    block = re.search(r"```sh\n(.*?)```", section, re.S).group(1)
    demo = REPO_ROOT / "data" / "demo"
    lines = [line.split("  #")[0].strip() for line in block.splitlines() if line.strip()]
    assert len(lines) >= 5
    for line in lines:
        command = (line.replace("build/sgdicp", str(cli))
                   .replace("SOURCE", str(demo / "car_cloud401.csv"))
                   .replace("REFERENCE", str(demo / "car_cloud400.csv"))
                   .replace("FOLDER2", str(folder)).replace("FOLDER", str(folder))
                   .replace("../shared/data", str(shared_data_dir())))
        done = subprocess.run(["bash", "-c", command], cwd=tmp_path, capture_output=True,
                              text=True, timeout=300)
        assert done.returncode == 0, f"README: {line}\n{done.stderr[-2000:]}"
