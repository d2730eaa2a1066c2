"""The README's code blocks run exactly as printed, and its accuracy table
holds docs/accuracy.md's figures. (Its ```rust block is a doctest of the
root crate: `cargo test -p twoscale-suite --doc`.)"""

import pathlib
import re
import subprocess
import sys

REPO = pathlib.Path(__file__).resolve().parents[2]
README = (REPO / "README.md").read_text(encoding="utf-8")
NUMBER = re.compile(r"\d+(?:\.\d+)?e-?\d+|\d{3,}")


def blocks(language):
    """The bodies of the README's fenced blocks opened by ```language."""
    return re.findall(rf"^```{language}\n(.*?)^```$", README, re.M | re.S)


def section(title):
    """The text of the README's section `## title`, up to the next one."""
    return README.split(f"\n## {title}\n", 1)[1].split("\n## ", 1)[0]


def test_python_block_runs_verbatim(tmp_path):
    (code,) = blocks("python")
    script = tmp_path / "readme.py"
    script.write_text(code, encoding="utf-8")
    # A fresh interpreter outside the repository: the installed package, and
    # the variant the block sets (the other tests set llvm_ad_rgb).
    done = subprocess.run([sys.executable, script], cwd=tmp_path, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    first = done.stdout.splitlines()[0]
    rgb = [float(x) for x in re.findall(r"[-+]?\d+\.\d*(?:e[-+]?\d+)?", first)]
    assert len(rgb) == 3, done.stdout
    assert rgb[0] > rgb[1] > rgb[2] > 0, done.stdout  # gold: red highest, as the Rust block asserts


def test_c_block_runs_verbatim(tmp_path):
    (code,) = blocks("c")
    source = tmp_path / "readme.c"
    source.write_text(code, encoding="utf-8")
    subprocess.run(["cargo", "build", "--release", "--locked", "-p", "twoscale-capi"], cwd=REPO, check=True)
    lib = REPO / "target" / "release"
    binary = tmp_path / "readme"
    subprocess.run(
        ["cc", "-std=c11", "-Wall", "-Wextra", "-Werror", "-pedantic", "-I", REPO / "capi" / "include",
         source, "-L", lib, "-ltwoscale_capi", f"-Wl,-rpath,{lib}", "-lm", "-o", binary],
        check=True,
    )
    done = subprocess.run([binary], cwd=tmp_path, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    words = done.stdout.split()
    assert words[:2] == ["rho", "="], done.stdout
    rgb = [float(x) for x in words[2:5]]
    assert rgb[0] > rgb[1] > rgb[2] > 0, done.stdout


def test_accuracy_figures_are_those_of_accuracy_md():
    report = (REPO / "docs" / "accuracy.md").read_text(encoding="utf-8")
    text = section("Accuracy")
    points = re.search(r"verify --points (\d+) --seed (\d+)", report)
    assert f"{int(points[1]):,}".replace(",", " ") in text and f"seed {points[2]}" in text
    rows = [line for line in text.splitlines() if line.startswith(("| T", "| BRDF"))]
    assert rows
    figures = [n for row in rows for n in NUMBER.findall(row)]
    assert len(figures) > 20
    missing = [n for n in figures if n not in report]
    assert not missing, f"README's accuracy table has figures docs/accuracy.md lacks: {missing}"
