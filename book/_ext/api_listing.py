"""Generate the API reference page's sections from the modules it names.

``book/api.md`` holds one fenced block ``{safepg-api}`` with a module name per line. Before
the page is parsed, this extension replaces the block with, for each module: a heading, the
first line of the module's docstring, an autosummary table of the module's public names and
the full autodoc entry of each. The names are the module's ``__all__``, so a name added
there appears on the page without editing it, and a module is added with one line.

An object that an earlier section already documents in full (``safepg.LQG`` is
``safepg.envs.LQG``) gets a one-line entry pointing there, which keeps the page short and
still gives the table's link a target.

Docstrings cite objects by the path of the module that defines them
(``safepg.envs.lqg.LQG.thesis_1d``) or by a name their module imports (``adaptive_pg`` in
:mod:`safepg.runner`), where the page documents them under the name users import
(``safepg.LQG.thesis_1d``, ``safepg.adaptive_pg``). A reference Sphinx cannot resolve is
imported here, and when it is an object the page documents, it links there; anything else
stays a missing reference (an error under ``-n -W``).

The docstrings write an absolute value as in plain text, ``|r_t|``, which is how ``help()``
shows them; to reStructuredText that is a substitution reference, an error when none is
defined. Outside inline markup, such a ``|...|`` is shown here as the literal text it is.

Each section's ``.. py:module::`` target is followed by the autosummary table, whose first node
is a ``tabular_col_spec`` (the table's LaTeX column spec). Docutils' ``PropagateTargets``
moves the target's id (``module-safepg.store``, where the module index and ``:mod:`` link)
onto that next node, and the HTML writer skips it whole, id included. :class:`KeepTargetIds`
moves such an id onto the table the spec belongs to, which the HTML writes.
"""

from __future__ import annotations

import dataclasses
import importlib
import inspect
import re
import weakref
from typing import Any

from docutils import nodes
from docutils.transforms import Transform
from docutils.transforms.references import PropagateTargets
from sphinx import addnodes

#: The book's tables do not wrap (safepg-book.css keeps numbers on one line); an autosummary
#: table's summaries must, and its names must not be broken letter by letter.
STYLE = """```{raw} html
<style>
.bd-article table.autosummary td { white-space: normal; }
.bd-article table.autosummary td:first-child, .bd-article table.autosummary td:first-child * {
  white-space: nowrap; overflow-wrap: normal; word-break: normal; }
/* Signatures carry their annotations, fully qualified, and Raises names an exception by its
   full path: on a phone they wrap inside the column. */
.bd-article dt.sig, .bd-article dt.sig span.pre, .bd-article dl.field-list > dd {
  white-space: normal; overflow-wrap: anywhere; }
</style>
```
"""

#: The fenced block that lists the modules: ```{safepg-api} ... ```, a module per line.
BLOCK = re.compile(r"^```\{safepg-api\}[ \t]*\n(?P<body>.*?)^```[ \t]*$", re.MULTILINE | re.DOTALL)


def block_modules(text: str) -> list[str]:
    """The module names listed in the page's ``{safepg-api}`` blocks, in order.

    Parameters
    ----------
    text : str
        The page's MyST source.

    Returns
    -------
    list of str
        One entry per non-empty line that is not a ``#`` comment.
    """
    names = []
    for match in BLOCK.finditer(text):
        for line in match["body"].splitlines():
            line = line.split("#", 1)[0].strip()
            if line:
                names.append(line)
    return names


def public_names(modname: str) -> list[str]:
    """The public names of a module: its ``__all__``, in its order.

    Parameters
    ----------
    modname : str
        Dotted name of an importable module.

    Returns
    -------
    list of str
        ``__all__`` without what the import did not define (an optional dependency missing).

    Raises
    ------
    ValueError
        The module has no ``__all__``: what it exports must be said there, not guessed.
    """
    module = importlib.import_module(modname)
    if not hasattr(module, "__all__"):
        raise ValueError(f"{modname} must define __all__ to be on the API page")
    return [n for n in module.__all__ if hasattr(module, n)]


def _kind(obj: Any) -> str:
    if inspect.isclass(obj):
        return "exception" if issubclass(obj, BaseException) else "class"
    if inspect.isroutine(obj):
        return "function"
    return "data"


_ROLE = {"class": "class", "exception": "exc", "function": "func", "data": "data"}


def module_markdown(modname: str, documented: dict[int, str], pointers: set[str] | None = None) -> str:
    """The MyST text of one module's section.

    Parameters
    ----------
    modname : str
        Dotted module name.
    documented : dict
        ``id(object)`` -> the full name it is documented under, for the classes and
        functions of earlier sections; this module's are added to it.
    pointers : set of str, optional
        Receives the full names given only a one-line entry pointing to another section.

    Returns
    -------
    str
        A heading, the docstring's first line, an autosummary table and one entry per name.
    """
    module = importlib.import_module(modname)
    summary = (inspect.getdoc(module) or "").strip().splitlines()
    lines = [f"({modname.replace('.', '-')})=", f"## `{modname}`", "", summary[0] if summary else "", ""]
    # A module target as well as the current module: docstrings cite modules (:mod:`safepg.store`).
    rst = [f".. py:module:: {modname}", "", ".. autosummary::", "   :nosignatures:", ""]
    names = public_names(modname)
    rst += [f"   {name}" for name in names] + [""]
    for name in names:
        obj = getattr(module, name)
        kind = _kind(obj)
        # Data (a version string, a constant) has no identity worth sharing: each module's own.
        first = documented.get(id(obj)) if kind != "data" else None
        if first is not None:
            if pointers is not None:
                pointers.add(f"{modname}.{name}")
            rst += [f".. py:{'function' if kind == 'function' else kind}:: {name}", "",
                    f"   The same object as :py:{_ROLE[kind]}:`{first}`.", ""]
            continue
        if kind != "data":
            documented[id(obj)] = f"{modname}.{name}"
        rst.append(f".. auto{kind}:: {name}")
        if kind in ("class", "exception"):
            rst.append("   :members:")
        rst.append("")
    lines += ["```{eval-rst}", *rst, "```", ""]
    return "\n".join(lines)


def expand(text: str, pointers: set[str] | None = None) -> str:
    """The page's text with each ``{safepg-api}`` block replaced by its modules' sections.

    Parameters
    ----------
    text : str
        The page's MyST source.
    pointers : set of str, optional
        Receives the names given only a one-line entry (see :func:`module_markdown`).

    Returns
    -------
    str
        The same text, the blocks expanded (unchanged when there is none).
    """
    documented: dict[int, str] = {}

    def sections(match: re.Match[str]) -> str:
        return "\n".join([STYLE] + [module_markdown(m, documented, pointers) for m in block_modules(match[0])])

    return BLOCK.sub(sections, text)


#: Inline markup (``literal``, :role:`text`, `text`), which may continue on the next line:
#: left as it is.
_INLINE = re.compile(r"``.+?``|(?::[\w:.+-]+:)?`[^`]+`_{0,2}", re.DOTALL)
#: ``|x|`` as docutils would read a substitution reference: on one line, no space inside its
#: bars, no word character against them outside.
_BARS = re.compile(r"(?<![\w|\\])\|(?=\S)([^|`\n]+?)(?<=\S)\|(?![\w|])")
#: A directive (``.. math::``) or a paragraph ending in ``::``: its indented body is not text.
_BLOCK_START = re.compile(r"^(\s*)(?:\.\. [\w:-]+::.*|.*::)$")


def _plain_text(text: str) -> str:
    out, pos = [], 0
    for match in _INLINE.finditer(text):
        out.append(_BARS.sub(r"``|\1|``", text[pos:match.start()]))
        out.append(match[0])
        pos = match.end()
    out.append(_BARS.sub(r"``|\1|``", text[pos:]))
    return "".join(out)


def plain_bars(lines: list[str]) -> list[str]:
    """A docstring's lines with each ``|...|`` of its running text made a literal.

    Parameters
    ----------
    lines : list of str
        The docstring, a line per entry.

    Returns
    -------
    list of str
        The same lines, ``|r_t|`` written ````|r_t|```` outside inline markup (which may
        span lines), directives (``.. math::``) and literal blocks, which are left as they are.
    """
    out: list[str] = []
    text: list[str] = []  # the running text since the last block
    body_indent: int | None = None  # inside a directive's or literal block's body

    def flush() -> None:
        if text:
            out.extend(_plain_text("\n".join(text)).split("\n"))
            text.clear()

    for line in lines:
        indent = len(line) - len(line.lstrip())
        if body_indent is not None and (not line.strip() or indent > body_indent):
            out.append(line)
            continue
        body_indent = None
        block = _BLOCK_START.match(line)
        if block and line.lstrip().startswith(".. "):
            flush()
            out.append(line)
            body_indent = len(block[1])
            continue
        text.append(line)
        if block:  # "...::" ends a paragraph that introduces a literal block
            flush()
            body_indent = len(block[1])
    flush()
    return out


def _docstring(app: Any, what: str, name: str, obj: Any, options: Any, lines: list[str]) -> None:
    if what in ("data", "attribute") and not inspect.isclass(obj) and lines:
        # A value with no comment of its own gets its type's docstring (``__version__`` would
        # be described by ``str``'s): that describes the type, not the value.
        doc = getattr(type(obj), "__doc__", None)
        own = inspect.cleandoc(doc).splitlines() if isinstance(doc, str) else []
        if own and [line for line in lines if line.strip()] == [line for line in own if line.strip()]:
            lines.clear()
    lines[:] = plain_bars(lines)


def _signature(app: Any, what: str, name: str, obj: Any, options: Any, signature: str | None,
               return_annotation: str | None) -> tuple[str | None, str | None] | None:
    """A dataclass's signature with each ``<factory>`` default written as the value it makes.

    ``<factory>`` is not Python: Sphinx would then give up parsing the signature and split it
    at every comma, annotations included (``Literal['scalar', 'coordinate']``).
    """
    if not signature or "<factory>" not in signature or not dataclasses.is_dataclass(obj):
        return None
    for f in dataclasses.fields(obj):
        if f.init and f.default_factory is not dataclasses.MISSING:
            signature = signature.replace("<factory>", repr(f.default_factory()), 1)
    return signature, return_annotation


def _source_read(app: Any, docname: str, source: list[str]) -> None:
    if "{safepg-api}" in source[0]:
        pointers: set[str] = set()
        source[0] = expand(source[0], pointers)
        # Kept in the environment, which outlives this read: an unchanged page is not re-read.
        app.env.safepg_api_pointers = pointers


def _merge(app: Any, env: Any, docnames: Any, other: Any) -> None:
    env.safepg_api_pointers = getattr(env, "safepg_api_pointers", set()) | getattr(other, "safepg_api_pointers", set())


def _import_dotted(name: str) -> Any:
    """The object a dotted name designates, or None."""
    parts = name.split(".")
    for i in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:i]))
        except ImportError:
            continue
        try:
            for attr in parts[i:]:
                obj = getattr(obj, attr)
        except AttributeError:
            return None
        return obj
    return None


def _identity(obj: Any) -> Any:
    # A classmethod or method read from its class is a new bound object at each access.
    return inspect.unwrap(getattr(obj, "__func__", obj))


#: Per build environment: :func:`_documented`, computed once per writing phase.
_DOCUMENTED: weakref.WeakKeyDictionary[Any, dict[int, str]] = weakref.WeakKeyDictionary()


def _documented(env: Any) -> dict[int, str]:
    """``id`` of each object the Python domain documents -> its documented name.

    The same for every missing reference of a writing phase (the domain's objects are all
    read by then), so computed once: importing every documented name again for each of the
    chapters' several hundred references took about 9 s of a full build."""
    if env not in _DOCUMENTED:
        _DOCUMENTED[env] = _documented_now(env)
    return _DOCUMENTED[env]


def _forget(app: Any, env: Any) -> None:
    # The pages were read again: what the domain documents may have changed.
    _DOCUMENTED.pop(env, None)


def _documented_now(env: Any) -> dict[int, str]:
    pointers = getattr(env, "safepg_api_pointers", set())
    found: dict[int, str] = {}
    # Full entries first, so that an object documented twice links to its full entry.
    objects = sorted(env.get_domain("py").objects.items(), key=lambda item: item[0] in pointers)
    for name, entry in objects:
        if entry.aliased or entry.objtype == "module":
            continue
        obj = _import_dotted(name)
        if obj is not None:
            found.setdefault(id(_identity(obj)), name)
    return found


def _missing_reference(app: Any, env: Any, node: Any, contnode: Any) -> Any:
    if node.get("refdomain") != "py" or node.get("reftype") == "mod":
        return None
    target = node["reftarget"]
    module, cls = node.get("py:module"), node.get("py:class")
    candidates = [target]
    if module:
        candidates += [f"{module}.{cls}.{target}"] if cls else []
        candidates.append(f"{module}.{target}")
    documented = _documented(env)
    for candidate in candidates:
        obj = _import_dotted(candidate)
        if obj is None:
            continue
        name = documented.get(id(_identity(obj)))
        if name is not None:
            py = env.get_domain("py")
            # "obj" matches any kind: an annotation's type alias (RNGLike) is documented as data.
            return py.resolve_xref(env, node["refdoc"], app.builder, "obj", name, node, contnode)
    return None


class KeepTargetIds(Transform):
    """Move the ids a target gave a ``tabular_col_spec`` onto the table that follows it.

    ``PropagateTargets`` hands a block-level target's ids to the next node, which is a
    ``tabular_col_spec`` when an autosummary table (or ``.. tabularcolumns::``) comes next.
    No HTML translator writes that node, so the id would be in the index and the links but
    not in the page. The spec describes the next table: that table carries the ids instead.
    """

    default_priority = PropagateTargets.default_priority + 1

    def apply(self, **kwargs: Any) -> None:
        for spec in list(self.document.findall(addnodes.tabular_col_spec)):
            if not spec["ids"]:
                continue
            table = spec.next_node(nodes.table, ascend=True)
            if table is None:
                continue
            for key in ("ids", "names"):
                table[key] = spec[key] + [v for v in table[key] if v not in spec[key]]
                spec[key] = []
            for node_id in table["ids"]:
                self.document.ids[node_id] = table


def setup(app: Any) -> dict[str, Any]:
    app.setup_extension("sphinx.ext.autodoc")
    app.setup_extension("sphinx.ext.autosummary")
    app.connect("source-read", _source_read)
    app.connect("env-merge-info", _merge)
    # Before numpydoc (priority 500) turns the sections into reStructuredText.
    app.connect("autodoc-process-docstring", _docstring, priority=400)
    app.connect("missing-reference", _missing_reference)
    app.connect("env-updated", _forget)
    app.connect("autodoc-process-signature", _signature)
    app.add_transform(KeepTargetIds)
    # A change to what the expansion writes (KeepTargetIds' module ids, the signatures' style)
    # is not a change to book/api.md: a new env_version has Sphinx read every page again
    # instead of reusing the old doctrees.
    return {"parallel_read_safe": True, "parallel_write_safe": True, "env_version": 3}
