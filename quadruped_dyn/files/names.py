"""Names derived from input (a URDF's file name, a robot's name): valid everywhere they are used.

A robot's name becomes C identifiers (``qd_<name>_M_full``), file names (``qd_<name>.c``) and
output folders (``<out>/<name>/``). CasADi refuses identifiers with ``__`` or a trailing ``_``;
``..`` or ``/`` in a file name leaves ``--out``; a 250-character stem breaks file systems;
non-ASCII and control characters break C and terminals. ``safe_name`` maps any text to a name of
ASCII letters, digits and single inner underscores, starting with a letter, at most
``MAX_NAME_CHARS`` long; a name it had to change gets a hash of the original text as a suffix, so
two different inputs never share a name. ``printable`` makes text safe to echo on a terminal.
"""

from __future__ import annotations

import hashlib
import re

#: Long enough for any robot's name; short enough that the longest derived identifier
#: (qd_<name>-r-FL_FR_BL_BR.c and C symbols such as qd_fd_r_FL_FR_BL_BR_work) stays
#: far below file-system (255 bytes) and C (63 significant characters in C99's external
#: identifiers ... 31 guaranteed; gcc has no limit) limits.
MAX_NAME_CHARS = 40
HASH_CHARS = 8


def _hash(text: str) -> str:
    return hashlib.sha256(text.encode("utf-8", "surrogateescape")).hexdigest()[:HASH_CHARS]


def is_safe_name(name: str) -> bool:
    """True if ``name`` can be used as is: a C identifier fragment and a file name."""
    return (len(name) <= MAX_NAME_CHARS and re.fullmatch(r"[A-Za-z][A-Za-z0-9]*(_[A-Za-z0-9]+)*", name) is not None)


def safe_name(text: str, fallback: str = "robot") -> str:
    """``text`` if ``is_safe_name``, else its ASCII letters and digits joined by single
    underscores (starting with a letter: ``fallback`` is prepended where needed), truncated, with
    ``_<hash of text>`` appended. Always ``is_safe_name``."""
    if is_safe_name(text):
        return text
    cleaned = "_".join(re.findall(r"[A-Za-z0-9]+", text))
    if not cleaned[:1].isalpha():
        cleaned = f"{fallback}_{cleaned}".rstrip("_")
    cleaned = cleaned[: MAX_NAME_CHARS - HASH_CHARS - 1].rstrip("_")
    return f"{cleaned}_{_hash(text)}"


def printable(text: object) -> str:
    """``str(text)`` with control characters (terminal escape sequences, newlines, DEL, C1) and
    unpaired surrogates (undecodable file-name bytes) shown as escapes, never sent raw."""
    out = []
    for ch in str(text):
        code = ord(ch)
        if code < 0x20 or 0x7F <= code < 0xA0 or 0xD800 <= code < 0xE000 or code in (0x2028, 0x2029):
            out.append(ch.encode("unicode_escape", "backslashreplace").decode("ascii")
                       if not 0xD800 <= code < 0xE000 else f"\\x{code - 0xDC00:02x}")
        else:
            out.append(ch)
    return "".join(out)


def comment_text(text: object) -> str:
    """``printable(text)`` that cannot end a C block comment nor open one inside it (a URDF's frame names are
    free text: ``*/`` becomes ``* /`` and ``/*`` becomes ``/ *``; gcc's -Wall -Werror, as in the generated
    Makefile, refuses a ``/*`` within a comment)."""
    text = printable(text)
    while "*/" in text or "/*" in text:  # '/*/' needs both, and a replacement must not form another
        text = text.replace("*/", "* /").replace("/*", "/ *")
    return text
