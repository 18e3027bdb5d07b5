"""The documentation: the MkDocs site builds without a warning, and the README stays a front page."""

import os
import pathlib
import re
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent


def test_the_site_builds_strictly_with_the_api_reference(tmp_path):
    site = tmp_path / "site"
    env = dict(os.environ, NO_MKDOCS_2_WARNING="1")
    done = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-q", "-d", str(site)],
                          cwd=ROOT, capture_output=True, text=True, env=env)
    assert done.returncode == 0, f"mkdocs build --strict failed:\n{done.stderr}"
    api = site / "api" / "index.html"
    assert api.is_file(), f"no {api.relative_to(tmp_path)} in the built site"
    assert "make_method" in api.read_text(encoding="utf-8")


def test_the_readme_is_short_and_its_docs_links_resolve():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    lines = text.splitlines()
    assert len(lines) <= 200, f"README.md has {len(lines)} lines; keep it a front page (at most 200)"
    links = re.findall(r"\]\((docs/[^)#\s]+)(?:#[^)\s]*)?\)", text)
    assert links, "README.md links into docs/"
    missing = sorted({link for link in links if not (ROOT / link).is_file()})
    assert not missing, f"README.md links to missing files: {missing}"


def test_the_api_reference_readable_in_the_repository_is_up_to_date():
    import subprocess
    import sys

    root = pathlib.Path(__file__).resolve().parents[1]
    run = subprocess.run([sys.executable, str(root / "tools" / "api_reference.py"), "--check"], capture_output=True,
                         text=True, cwd=root)
    assert run.returncode == 0, run.stderr
    text = (root / "docs" / "api-reference.md").read_text()
    assert "### `make_method`" in text and "### `MethodSpec`" in text and "### `load_estimate`" in text
