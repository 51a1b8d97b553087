"""The documentation site shows the docstrings' Sphinx roles as the code they name
(docs_hooks/sphinx_roles.py, a hook of mkdocs.yml)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def hook():
    spec = importlib.util.spec_from_file_location("sphinx_roles", ROOT / "docs_hooks" / "sphinx_roles.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_a_rendered_role_shows_as_its_code():
    html = "<p>Build a :class:<code>RunSpec</code> with :meth:<code>RunSpec.of</code>.</p>"
    assert hook().without_roles(html) == "<p>Build a <code>RunSpec</code> with <code>RunSpec.of</code>.</p>"


def test_a_tilde_target_shows_its_last_part_and_py_roles_are_read_too():
    html = ":py:func:<code>~empathy_zoo.exact_solver.optimum</code> and :data:<code>~empathy_zoo.metrics.METRIC_NAMES</code>"
    assert hook().without_roles(html) == "<code>optimum</code> and <code>METRIC_NAMES</code>"


def test_text_that_is_no_role_is_left_as_it_is():
    html = "<p>ratio 1:2 and <code>a:b</code>; the key :rate: and :class: alone</p>"
    assert hook().without_roles(html) == html


def test_the_site_configuration_names_the_hook():
    assert "docs_hooks/sphinx_roles.py" in (ROOT / "mkdocs.yml").read_text()
