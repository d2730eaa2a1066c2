"""What a user installs and cites: the package's version is the crates',
its metadata gives the licence and carries both texts, and the changelog's
first release is this version (issue 47 item 8)."""

import importlib.metadata
import pathlib
import re
import tomllib

import twoscale

REPO = pathlib.Path(__file__).resolve().parents[2]
VERSION = tomllib.loads((REPO / "Cargo.toml").read_text(encoding="utf-8"))["workspace"]["package"]["version"]


def test_version_is_the_crates():
    assert twoscale.__version__ == VERSION
    assert importlib.metadata.version("twoscale") == VERSION
    assert "__version__" in twoscale.__all__


def test_metadata_gives_the_licence_and_both_texts():
    workspace = tomllib.loads((REPO / "Cargo.toml").read_text(encoding="utf-8"))
    licence = workspace["workspace"]["package"]["license"]
    assert licence == "MIT OR Apache-2.0"
    meta = importlib.metadata.metadata("twoscale")
    assert meta["License-Expression"] == licence
    files = [str(f) for f in importlib.metadata.files("twoscale") or []]
    for name in ("LICENSE-MIT", "LICENSE-APACHE"):
        assert any(f.endswith(name) for f in files), files
        assert (REPO / name).is_file()
    assert "Apache License" in (REPO / "LICENSE-APACHE").read_text(encoding="utf-8")
    assert "Permission is hereby granted" in (REPO / "LICENSE-MIT").read_text(encoding="utf-8")


def test_every_crate_gives_the_licence():
    """Each Cargo.toml of the repository (the workspace's members, the fuzz
    crate and the crates CI builds outside the workspace) states it."""
    manifests = [p for pattern in ("Cargo.toml", "*/Cargo.toml", ".ci/*/Cargo.toml", "examples/*/Cargo.toml")
                 for p in REPO.glob(pattern)]
    assert len(manifests) == 10, manifests
    for manifest in manifests:
        package = tomllib.loads(manifest.read_text(encoding="utf-8")).get("package")
        if package is None:
            continue
        assert package.get("license") in ({"workspace": True}, "MIT OR Apache-2.0"), manifest


def test_the_changelog_opens_with_this_release():
    text = (REPO / "CHANGELOG.md").read_text(encoding="utf-8")
    releases = re.findall(r"^## (\d+\.\d+\.\d+)\b", text, re.M)
    assert releases and releases[0] == VERSION, releases
    assert "## Developer history" in text
    assert text.index(f"## {VERSION}") < text.index("## Developer history")
