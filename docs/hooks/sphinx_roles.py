"""Griffe extension of the documentation site: Sphinx cross-reference roles in docstrings become links.

fdikit's docstrings use the numpydoc/Sphinx roles (``:func:`~fdikit.simulate.simulate```, ``:class:`Trace```), which
read well in ``help()`` and in an IDE.  mkdocstrings renders Markdown, where such a role shows as literal text, so
this extension rewrites every role, once the package is loaded, into an autorefs link ``[`simulate`][fdikit.simulate.
simulate]`` when the target is an fdikit object (resolved as written, then relative to the object's class, module and
package), and into plain code ```simulate``` otherwise (numpy, scipy, python-control targets), so that a role never
makes a broken link.  Written by hand: no maintained package converts Sphinx roles for mkdocstrings.
"""

from __future__ import annotations

import re

import griffe

ROLE = re.compile(r":(?:py:)?(func|class|meth|mod|attr|data|exc|obj|const|ref|term):`(~?)([^`<>]+?)(?:\s*<([^`>]+)>)?`")


def _rendered(collection, path: str) -> str | None:
    """The path of the page anchor of ``path`` on the API pages, or None when the site does not show that object.

    The API pages (tools/api_pages.py) show every module that is not a package, the names in its ``__all__`` that it
    defines, and their public members that have a docstring; an imported name stands for the object it imports.
    """
    try:
        obj = collection.get_member(path)
        if obj.is_alias:
            obj = obj.final_target
    except Exception:  # noqa: BLE001 - any failure to find or resolve means "not shown"
        return None
    if obj.is_module:
        return obj.path if not obj.is_init_module and obj.path != "fdikit.cli" else None
    parent = obj.parent
    if parent is None or obj.name.startswith("_") or not obj.docstring:
        return None
    if parent.is_module:
        exports = parent.exports or []
        return obj.path if obj.name in exports and _rendered(collection, parent.path) else None
    return obj.path if parent.is_class and _rendered(collection, parent.path) else None


def _candidates(obj: griffe.Object, target: str) -> list[str]:
    scopes = []
    node = obj
    while node is not None:
        scopes.append(node.path)
        node = node.parent
    return [target] + [f"{scope}.{target}" for scope in scopes]


class SphinxRoles(griffe.Extension):
    """Rewrite Sphinx roles in every docstring of a loaded package (see the module docstring)."""

    def on_package(self, *, pkg: griffe.Module, loader: griffe.GriffeLoader, **kwargs) -> None:  # noqa: ARG002
        collection = loader.modules_collection
        self._walk(pkg, collection, set())

    def _walk(self, obj, collection, seen: set[str]) -> None:
        if obj.path in seen or obj.is_alias:
            return
        seen.add(obj.path)
        if obj.docstring is not None:
            obj.docstring.value = ROLE.sub(lambda m: self._replace(m, obj, collection), obj.docstring.value)
        for member in obj.members.values():
            if not member.is_alias:
                self._walk(member, collection, seen)

    @staticmethod
    def _replace(match: re.Match, obj, collection) -> str:
        role, tilde, text, explicit = match.groups()
        target = (explicit or text).strip().rstrip("()")
        shown = text.strip() if explicit else (target.rsplit(".", 1)[-1] if tilde else text.strip())
        if role in ("ref", "term"):
            return f"`{shown}`"
        start = obj.parent if obj.kind is griffe.Kind.ATTRIBUTE and obj.parent is not None else obj
        for path in _candidates(start, target.lstrip(".")):
            anchor = _rendered(collection, path)
            if anchor is not None:
                return f"[`{shown}`][{anchor}]"
        return f"`{shown}`"
