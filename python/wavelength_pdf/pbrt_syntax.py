"""The pbrt-v4 scene syntax: tokens, statements and their parameter lists (design §5).

One module for every reader of scenes: the optimizer's emitter scan
(:mod:`wavelength_pdf.scene_spectra`) and the evaluation's scene copy
(:mod:`wavelength_pdf.evaluation.scene_edit`). Written here because no maintained Python
package reads pbrt-v4 scenes; it is a tokenizer plus a walk over statements, not a scene
builder. Errors are :class:`~wavelength_pdf.spectra.SpectrumError` naming ``file:line``.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from wavelength_pdf.spectra import SpectrumError

__all__ = ["Token", "Param", "Statement", "tokenize", "statements", "split_params"]


@dataclass(frozen=True)
class Token:
    """One lexical token of a pbrt file: ``kind`` is 'str', 'num', 'word', '[' or ']'."""

    kind: str
    text: str
    path: Path
    line: int
    start: int = 0  # character offsets of the token in its file's text (quotes included)
    end: int = 0

    @property
    def where(self) -> str:
        return f"{self.path}:{self.line}"



# --------------------------------------------------------------------------------------
# Tokens
# --------------------------------------------------------------------------------------

_TOKEN = re.compile(
    r"""
      (?P<ws>[ \t\r\f\v]+)
    | (?P<nl>\n)
    | (?P<comment>\#[^\n]*)
    | (?P<str>"(?:[^"\\\n]|\\.)*")
    | (?P<open>\[)
    | (?P<close>\])
    | (?P<atom>[^\s\[\]"#]+)
    | (?P<bad>")
    """,
    re.VERBOSE,
)
_NUMBER = re.compile(r"^[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$")
_ESCAPES = {"n": "\n", "t": "\t", "b": "\b", "f": "\f", "r": "\r", "\\": "\\", '"': '"', "'": "'"}


def tokenize(text: str, path: Path) -> list[Token]:
    """Split pbrt scene text into tokens (comments dropped, strings unquoted)."""
    tokens: list[Token] = []
    line = 1
    for m in _TOKEN.finditer(text):
        kind = m.lastgroup
        s = m.group()
        if kind == "nl":
            line += 1
        elif kind in ("ws", "comment"):
            pass
        elif kind == "str":
            body = re.sub(r"\\(.)", lambda e: _ESCAPES.get(e.group(1), e.group(1)), s[1:-1])
            tokens.append(Token("str", body, path, line, m.start(), m.end()))
        elif kind == "open":
            tokens.append(Token("[", s, path, line, m.start(), m.end()))
        elif kind == "close":
            tokens.append(Token("]", s, path, line, m.start(), m.end()))
        elif kind == "atom":
            tokens.append(Token("num" if _NUMBER.match(s) else "word", s, path, line, m.start(), m.end()))
        else:
            raise SpectrumError(f"{path}:{line}: unterminated string")
    return tokens


# --------------------------------------------------------------------------------------
# Statements
# --------------------------------------------------------------------------------------

@dataclass
class Param:
    type: str
    name: str
    values: list[Token]
    decl: Token

    @property
    def where(self) -> str:
        return self.decl.where


@dataclass
class Statement:
    """A directive and its items: tokens, or token lists for bracketed arrays."""

    directive: Token
    items: list
    args: list[Token] = field(default_factory=list)      # positional arguments
    params: list[Param] = field(default_factory=list)   # the parameter list

    def first_string(self) -> str | None:
        it = self.items[0] if self.items else None
        if isinstance(it, list) and len(it) == 1:
            it = it[0]
        return it.text if isinstance(it, Token) and it.kind == "str" else None


def statements(tokens: list[Token]):
    """Group tokens into statements: a directive word, its arguments, its parameter list."""
    i, n = 0, len(tokens)
    while i < n:
        tok = tokens[i]
        if tok.kind != "word" or tok.text in ("true", "false"):
            raise SpectrumError(f"{tok.where}: unexpected {tok.text!r} (expected a directive)")
        j = i + 1
        items: list[Token | list[Token]] = []
        while j < n and not (tokens[j].kind == "word" and tokens[j].text not in ("true", "false")):
            if tokens[j].kind == "[":
                k = j + 1
                while k < n and tokens[k].kind != "]":
                    if tokens[k].kind == "[":
                        raise SpectrumError(f"{tokens[k].where}: nested '[' is not allowed")
                    k += 1
                if k == n:
                    raise SpectrumError(f"{tokens[j].where}: '[' is never closed")
                items.append(tokens[j + 1:k])
                j = k + 1
            elif tokens[j].kind == "]":
                raise SpectrumError(f"{tokens[j].where}: ']' without '['")
            else:
                items.append(tokens[j])
                j += 1
        yield Statement(tok, items)
        i = j


_PARAM_DECL = re.compile(r"^\s*([A-Za-z][\w]*)\s+([^\s]+)\s*$")


def split_params(st: Statement, n_positional: int) -> Statement:
    """Fill ``st.args`` with ``n_positional`` quoted arguments, ``st.params`` with the
    ``"type name" value`` pairs that follow (only done for the directives read here, so
    other statements never need to be understood)."""
    items, directive = st.items, st.directive
    for k in range(n_positional):
        it = items[k] if k < len(items) else None
        if not (isinstance(it, Token) and it.kind == "str"):
            raise SpectrumError(f"{directive.where}: {directive.text} needs a quoted "
                                f"type name as argument {k + 1}")
        st.args.append(it)
    k = n_positional
    while k < len(items):
        decl = items[k]
        if not (isinstance(decl, Token) and decl.kind == "str" and _PARAM_DECL.match(decl.text)):
            where = decl.where if isinstance(decl, Token) else (decl[0].where if decl else directive.where)
            got = decl.text if isinstance(decl, Token) else "[...]"
            raise SpectrumError(f"{where}: expected a parameter \"type name\" in "
                                f"{directive.text}, got {got!r}")
        if k + 1 >= len(items):
            raise SpectrumError(f"{decl.where}: parameter \"{decl.text}\" has no value")
        ptype, pname = _PARAM_DECL.match(decl.text).groups()
        val = items[k + 1]
        st.params.append(Param(ptype, pname, val if isinstance(val, list) else [val], decl))
        k += 2
    return st


# --------------------------------------------------------------------------------------
# Spectra of emitter parameters
# --------------------------------------------------------------------------------------
