"""The README's code blocks run exactly as printed and print the same
numbers, and its accuracy table holds docs/accuracy.md's figures. (Its
```rust block is also a doctest of the root crate: `cargo test -p
twoscale-suite --doc`.)"""

import os
import pathlib
import re
import shutil
import subprocess
import sys

import numpy as np

REPO = pathlib.Path(__file__).resolve().parents[2]
README = (REPO / "README.md").read_text(encoding="utf-8")
NUMBER = re.compile(r"\d+(?:\.\d+)?e-?\d+|\d{3,}")


def blocks(language):
    """The bodies of the README's fenced blocks opened by ```language."""
    return re.findall(rf"^```{language}\n(.*?)^```$", README, re.M | re.S)


def section(title):
    """The text of the README's section `## title`, up to the next one."""
    return README.split(f"\n## {title}\n", 1)[1].split("\n## ", 1)[0]


FLOAT = re.compile(r"[-+]?\d+\.\d*(?:e[-+]?\d+)?|[-+]?\d+(?:e[-+]?\d+)?")


def first_numbers(text, count=3):
    """The first `count` numbers of the first line of `text`."""
    numbers = [float(x) for x in FLOAT.findall(text.splitlines()[0])]
    assert len(numbers) >= count, text
    return numbers[:count]


def run_python_block(tmp_path):
    (code,) = blocks("python")
    script = tmp_path / "readme.py"
    script.write_text(code, encoding="utf-8")
    # A fresh interpreter outside the repository: the installed package, and
    # the variant the block sets (the other tests set llvm_ad_rgb).
    done = subprocess.run([sys.executable, script], cwd=tmp_path, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    return done.stdout


def run_c_block(tmp_path, cargo_build):
    (code,) = blocks("c")
    source = tmp_path / "readme.c"
    source.write_text(code, encoding="utf-8")
    lib = cargo_build("twoscale-capi")
    binary = tmp_path / "readme"
    subprocess.run(
        ["cc", "-std=c11", "-Wall", "-Wextra", "-Werror", "-pedantic", "-I", REPO / "capi" / "include",
         source, "-L", lib, "-ltwoscale_capi", f"-Wl,-rpath,{lib}", "-lm", "-o", binary],
        check=True,
    )
    done = subprocess.run([binary], cwd=tmp_path, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    return done.stdout


def run_rust_block(tmp_path, cargo):
    """The Rust block as `src/main.rs` of a new crate whose dependency is the
    README's line (REPO replaced by the repository), run with
    `cargo run --release` (the workspace's lock file, its own target)."""
    (code,) = blocks("rust")
    (line,) = re.findall(r"^`(twoscale = \{ path = \"REPO/runtime\".*\})`\.?$", README, re.M)
    crate = tmp_path / "readme-crate"
    (crate / "src").mkdir(parents=True)
    (crate / "src" / "main.rs").write_text(code, encoding="utf-8")
    (crate / "Cargo.toml").write_text(
        '[package]\nname = "readme"\nversion = "0.0.0"\nedition = "2024"\npublish = false\n\n'
        f"[dependencies]\n{line.replace('REPO', REPO.as_posix())}\n\n[workspace]\n",
        encoding="utf-8",
    )
    shutil.copy(REPO / "Cargo.lock", crate / "Cargo.lock")
    done = subprocess.run(
        [cargo, "run", "--release", "--quiet", "--manifest-path", crate / "Cargo.toml"],
        env={**os.environ, "CARGO_TARGET_DIR": str(REPO / "target" / "readme-crate")},
        capture_output=True, text=True,
    )
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_python_block_runs_verbatim(tmp_path):
    out = run_python_block(tmp_path)
    rgb = first_numbers(out)
    assert rgb[0] > rgb[1] > rgb[2] > 0, out  # gold: red highest
    # `print(bsdf)` shows the material it was built from (its repr).
    assert 'twoscale.Material.preset("gold-rough")' in out, out


def test_c_block_runs_verbatim(tmp_path, cargo_build):
    out = run_c_block(tmp_path, cargo_build)
    words = out.split()
    assert words[:2] == ["rho", "="], out
    rgb = [float(x) for x in words[2:5]]
    assert rgb[0] > rgb[1] > rgb[2] > 0, out


def test_the_three_quick_starts_print_the_same_numbers(tmp_path, cargo, cargo_build):
    """One preset, one answer: the Rust, Python and C blocks evaluate the
    same preset at the same directions and print the same ρ. Rust and NumPy
    print the shortest decimal that rounds back to the float32, so theirs
    agree digit for digit; C's `%g` keeps 6 significant digits."""
    rust = first_numbers(run_rust_block(tmp_path, cargo))
    python = first_numbers(run_python_block(tmp_path))
    c = first_numbers(run_c_block(tmp_path, cargo_build))
    assert rust == python, (rust, python)
    for r, v in zip(rust, c):
        assert float(f"{float(np.float32(r)):.6g}") == v, (rust, c)


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


def test_what_installing_needs_comes_first():
    """A newcomer reads what a source install needs before the quick starts:
    the Rust toolchain, cbindgen (the version CI installs) and the LLVM that
    Mitsuba's llvm variants load (also in docs/python.md)."""
    titles = re.findall(r"^## (.+)$", README, re.M)
    assert titles.index("What installing needs") < titles.index("Quick start"), titles
    text = section("What installing needs")
    ci = (REPO / ".ci" / "run").read_text(encoding="utf-8")
    (cbindgen,) = set(re.findall(r"cargo install cbindgen --version [\d.]+ --locked", ci))
    for needed in ("Rust toolchain", cbindgen, "DRJIT_LIBLLVM_PATH", "maturin build"):
        assert needed in text, needed
    assert cbindgen in (REPO / "capi" / "tests" / "c" / "run.sh").read_text(encoding="utf-8")
    assert "DRJIT_LIBLLVM_PATH" in (REPO / "docs" / "python.md").read_text(encoding="utf-8")


def test_ci_installs_with_the_readme_s_commands():
    """CI installs the package with nothing but the README's commands (issue
    47): every `pip install …`, `maturin build …` and `python -m pytest …` the
    README prints is a command line of .ci/run, verbatim, and .ci/run's pip
    installs no package by hand besides them."""
    printed = set(re.findall(r"`((?:pip install|maturin build|python -m pytest) [^`]+?)`", README))
    printed = {part.strip() for command in printed for part in command.split("&&")}
    assert len(printed) >= 6, printed
    ci = (REPO / ".ci" / "run").read_text(encoding="utf-8")
    lines = [line.split("#")[0].strip() for line in ci.splitlines()]
    for command in printed:
        assert any(line.startswith(command) for line in lines), command
    installs = {line for line in lines if re.match(r"(python3? -m )?pip3? install", line)}
    extra = {line for line in installs if not any(line.startswith(c) for c in printed)}
    assert extra == {'pip install "$wheel[test]"'}, extra
