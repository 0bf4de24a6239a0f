"""book/_ext/static_digest.py: an edit to the book's own CSS or JavaScript rewrites every page.

Sphinx copies the static files only when it writes a page. The digest is a configuration
value of the ``html`` kind, which Sphinx's HTML builder hashes into its build info: a
changed digest makes every page out of date.
"""

from __future__ import annotations

from pathlib import Path

from script_module import load
from sphinx.builders.html import BuildInfo
from sphinx.config import Config

ROOT = Path(__file__).resolve().parents[1]


def _extension():
    return load("book/_ext/static_digest.py")


def test_the_digest_follows_every_file_of_the_folder(tmp_path):
    digest = _extension().static_digest
    (tmp_path / "a.js").write_text("one")
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "b.css").write_text("two")
    first = digest([tmp_path])
    assert digest([tmp_path]) == first
    (tmp_path / "a.js").write_text("one!")
    edited = digest([tmp_path])
    assert edited != first
    (tmp_path / "sub" / "b.css").rename(tmp_path / "sub" / "c.css")
    assert digest([tmp_path]) not in (first, edited)


def test_a_new_digest_makes_the_html_build_info_differ():
    """What Sphinx compares to decide that every page must be written again."""
    ext = _extension()

    class App:
        def __init__(self) -> None:
            self.values: dict = {}

        def add_config_value(self, name, default, rebuild):
            self.values[name] = (default, rebuild)

        def connect(self, event, handler):
            self.handler = handler

    app = App()
    ext.setup(app)
    assert app.values["safepg_static_digest"][1] == "html"

    def info(digest: str) -> BuildInfo:
        config = Config({}, {})
        config.add("safepg_static_digest", "", "html", ())
        config.init_values()
        config.safepg_static_digest = digest
        return BuildInfo(config, None, frozenset({"html"}))

    assert info("a") == info("a")
    assert info("a") != info("b")


def test_the_book_loads_the_extension_and_it_reads_our_static_folder():
    config = (ROOT / "_config.yml").read_text()
    assert "static_digest: book/_ext" in config
    ext = _extension()
    for folder in ext.OWN_STATIC:
        assert folder in config, f"{folder} is not in html_static_path"
        assert any((ROOT / folder).iterdir())
