"""The bibliography: every published source skyscatter implements or checks against, under a short key.

Docstrings cite a source by its key in brackets (``[Preetham1999] A.1``, ``[Bruneton2008] Eq. 16``) with the
section, equation or table; the full reference is written once, in ``skyscatter/data/references.json``, and shown
in ``docs/references.md`` (:func:`markdown`, checked equal by the tests). The sky-model registry's citations come
from here (:func:`cite`).
"""

from __future__ import annotations

import json
from functools import lru_cache
from importlib import resources
from typing import Any

__all__ = ["cite", "entries", "markdown", "reference"]


@lru_cache(maxsize=1)
def entries() -> dict[str, dict[str, Any]]:
    """The bibliography: key -> ``authors``, ``year``, ``title``, ``venue`` and optionally ``doi`` or ``url``."""
    text = resources.files("skyscatter").joinpath("data/references.json").read_text(encoding="utf-8")
    data: dict[str, dict[str, Any]] = json.loads(text)
    return data


def reference(key: str) -> str:
    """The full reference of ``key`` as one line: ``authors (year), title, venue, doi:...``."""
    try:
        e = entries()[key]
    except KeyError:
        raise KeyError(f"no reference {key!r} in the bibliography (skyscatter/data/references.json)") from None
    link = f", doi:{e['doi']}" if "doi" in e else (f", {e['url']}" if "url" in e else "")
    return f"{e['authors']} ({e['year']}), {e['title']}, {e['venue']}{link}"


def cite(*keys: str, note: str = "") -> str:
    """The full references of ``keys`` joined by ``"; "``, with an optional leading note (a registry citation)."""
    text = "; ".join(reference(k) for k in keys)
    return f"{note} {text}" if note else text


def markdown() -> str:
    """``docs/references.md``: the bibliography as a Markdown list, by key."""
    lines = ["# References", "",
             "Every published source skyscatter implements or checks against. Docstrings cite them by key, in "
             "brackets", "(`[Preetham1999] A.1`), with the section, equation or table. Written from "
             "`src/skyscatter/data/references.json`", "(`python -c \"import skyscatter.references as r; "
             "print(r.markdown(), end='')\" > docs/references.md`).", ""]
    for key, e in entries().items():
        link = (f", [doi:{e['doi']}](https://doi.org/{e['doi']})" if "doi" in e
                else (f", <{e['url']}>" if "url" in e else ""))
        lines.append(f"- **[{key}]** {e['authors']} ({e['year']}), *{e['title']}*, {e['venue']}{link}.")
    return "\n".join(lines) + "\n"
