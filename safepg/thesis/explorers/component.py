"""The reproduction's explorers on the core's component (:mod:`safepg.explorers.component`).

The component itself (the controls, the plots, the page's runtime and safepg's closed forms in
JavaScript, the kernel view) is the core's; this module reads the reproduction's own
JavaScript (the page learner, the Chapter 5 pages, the WebAssembly kernel) from
``safepg/thesis/explorers/static/``, and the core's shared files (``lib.js``, ``runtime.js``,
``upsilon_compute.js``) from ``safepg/explorers/static/``.
"""

from __future__ import annotations

from functools import cache
from importlib import resources

from safepg.explorers import component
from safepg.explorers.component import Checkbox, Explorer, Plot, Select, Slider

#: The package whose ``static/`` folder holds the reproduction's own JavaScript.
PACKAGE = "safepg.thesis.explorers"


def _here(name: str) -> bool:
    return resources.files(PACKAGE).joinpath("static", name).is_file()


@cache
def static_text(name: str) -> str:
    """The text of a file of the reproduction's ``static/`` folder, or of the core's (``runtime.js``)."""
    return component.static_text(name, PACKAGE if _here(name) else component.PACKAGE)


def static_bytes(name: str) -> bytes:
    """The bytes of a binary file of the reproduction's ``static/`` folder (``"lqg2d_kernel.wasm"``)."""
    return component.static_bytes(name, PACKAGE)


__all__ = ["Checkbox", "Explorer", "Plot", "Select", "Slider", "static_bytes", "static_text"]
