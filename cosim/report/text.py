"""Words and numbers of the report: times in ms or us, values with their unit, state names, descriptions.

No plotting and no HTML layout here, so that each rule is tested on its own:

* :func:`time_text`: an instant or a duration in the unit that suits it (``319 ms``, ``12.5 us``),
  exact to the ns when the value is;
* :func:`humanize_ns`: the ``<number> ns`` of a check's detail text said in that unit;
* :func:`value_text`: a value with its unit (``20 slots``, ``1.5 mm``);
* :func:`state_names`: the names of an ``int`` signal's codes, read from its description (a list
  ``0 idle, 1 running`` or ``9 frozen, 11 armed``, a Python path to an ``IntEnum``, or
  ``(<Name> codes)`` naming one of cosim's ``IntEnum`` classes);
* :func:`rst_html`: a description in reStructuredText as HTML (paragraphs, lists, literal blocks,
  inline markup), so that no markup shows.
"""

from __future__ import annotations

import html
import importlib
import re
import sys
from collections.abc import Mapping
from enum import IntEnum
from functools import cache

#: (factor to ns, unit), largest first: a time is said in the first unit it reaches one of.
_TIME_UNITS = ((10**9, "s"), (10**6, "ms"), (10**3, "us"), (1, "ns"))


def time_text(t_ns: float, *, unit: str | None = None) -> str:
    """A time in ns said in s, ms, us or ns (the largest unit it reaches one of, or ``unit``), exactly.

    Examples
    --------
    >>> time_text(319_000_000), time_text(12_500), time_text(23_437_499), time_text(0), time_text(4.4e9)
    ('319 ms', '12.5 us', '23.437499 ms', '0 s', '4.4 s')
    >>> time_text(1_500_000, unit="us")
    '1,500 us'
    """
    if unit is None:
        magnitude = abs(t_ns)
        factor, unit = next(((f, u) for f, u in _TIME_UNITS if magnitude >= f), (10**9, "s"))
    else:
        factor = dict((u, f) for f, u in _TIME_UNITS)[unit]
    return f"{_exact(t_ns, factor)} {unit}"


def _exact(value: float, factor: int) -> str:
    """``value / factor`` with the digits it has (at most 9 decimals), thousands separated."""
    if float(value).is_integer():
        whole, rest = divmod(abs(int(value)), factor)
        sign = "-" if value < 0 else ""
        if not rest:
            return f"{sign}{whole:,}"
        digits = len(str(factor)) - 1
        return f"{sign}{whole:,}." + f"{rest:0{digits}d}".rstrip("0")
    return f"{value / factor:,.9g}"


def humanize_ns(text: str) -> str:
    """The ``<number> ns`` of a text in the unit that suits each (``from 319000000 to 361000000 ns``
    becomes ``from 319 ms to 361 ms``).

    Examples
    --------
    >>> humanize_ns("pokeys.underrun > 0 from 319000000 to 361000000 ns (highest 1)")
    'pokeys.underrun > 0 from 319 ms to 361 ms (highest 1)'
    >>> humanize_ns("pulse 5 only 300 ns after pulse 4 at 1200500 ns")
    'pulse 5 only 300 ns after pulse 4 at 1.2005 ms'
    """
    def t(number: str) -> str:
        return time_text(float(number))

    number = r"(-?\d+(?:\.\d+)?)"
    text = re.sub(rf"\bfrom {number} to {number} ns\b", lambda m: f"from {t(m[1])} to {t(m[2])}", text)
    text = re.sub(rf"\[{number}, {number}\) ns\b", lambda m: f"[{t(m[1])}, {t(m[2])})", text)
    return re.sub(rf"(?<![\w.]){number} ns\b", lambda m: t(m[1]), text)


def number_text(value: object) -> str:
    """A number as a reader wants it: integers with thousands separators, floats to 6 significant digits.

    Examples
    --------
    >>> number_text(42000000), number_text(0.25), number_text(1/3), number_text("never > 0"), number_text(True)
    ('42,000,000', '0.25', '0.333333', 'never > 0', 'True')
    """
    if isinstance(value, bool) or not isinstance(value, int | float):
        return str(value)
    if isinstance(value, float) and not value.is_integer():
        return f"{value:,.6g}"
    if isinstance(value, float) and abs(value) >= 1e16:
        return f"{value:.6g}"
    return f"{int(value):,}"


def value_text(value: object, unit: str = "", states: Mapping[int, str] | None = None) -> str:
    """A value with its unit, or the name of its state; ``ns`` values as times.

    Examples
    --------
    >>> value_text(20, "slots"), value_text(42000000, "ns"), value_text(2, "", {2: "RUNNING"}), value_text(3)
    ('20 slots', '42 ms', 'RUNNING (2)', '3')
    """
    if states and isinstance(value, int | float) and float(value).is_integer() and int(value) in states:
        return f"{states[int(value)]} ({int(value)})"
    if unit == "ns" and isinstance(value, int | float) and not isinstance(value, bool):
        return time_text(value)
    text = number_text(value)
    return f"{text} {unit}" if unit and isinstance(value, int | float) and not isinstance(value, bool) else text


_LISTED = re.compile(r"(?<![\w.^-])(-?\d+)\s*(?:=\s*|:\s*)?([A-Za-z][\w-]*(?: [a-z][\w-]*)?)(?=\s*(?:,|;|\)|$))")


def state_names(description: str) -> dict[int, str]:
    """The names of an int signal's codes as its description gives them (empty when it gives none).

    Examples
    --------
    >>> state_names("method digit of the entry: 9 frozen, 11 armed, 10 running")
    {9: 'frozen', 11: 'armed', 10: 'running'}
    >>> state_names("the job: 0 idle, 1 running, 2 done, 3 error stop (cosim.job.JobState)")[3]
    'ERROR'
    >>> state_names("queued slots in the 128-slot buffer")
    {}
    """
    enum = _enum_named(description)
    if enum is not None:
        return {int(member): member.name for member in enum}
    found = {int(m[1]): m[2] for m in _LISTED.finditer(description)}
    return found if len(found) >= 2 else {}


def _enum_named(description: str) -> type[IntEnum] | None:
    for path in re.findall(r"\b((?:[a-z_]\w*\.)+[A-Z]\w*)\b", description):
        module, _, name = path.rpartition(".")
        try:
            found = getattr(importlib.import_module(module), name, None)
        except ImportError:
            continue
        if isinstance(found, type) and issubclass(found, IntEnum):
            return found
    for name in re.findall(r"\b([A-Z][A-Za-z]+) codes\b", description):
        found = _cosim_enums().get(name)
        if found is not None:
            return found
    return None


@cache
def _cosim_enums() -> dict[str, type[IntEnum]]:
    """cosim's ``IntEnum`` classes by name, from the modules this process has imported (the
    controllers' when the runs were made here) and the controllers' ``states`` modules."""
    import pkgutil

    import cosim.controllers

    for info in pkgutil.walk_packages(cosim.controllers.__path__, "cosim.controllers."):
        if info.name.rsplit(".", 1)[-1] == "states":
            importlib.import_module(info.name)
    found: dict[str, type[IntEnum]] = {}
    for name, module in sorted(sys.modules.items()):
        if not (name == "cosim" or name.startswith("cosim.")) or module is None:
            continue
        for value in list(vars(module).values()):
            if isinstance(value, type) and issubclass(value, IntEnum) and value.__module__ == name:
                found.setdefault(value.__name__, value)
    return found


# -- reStructuredText, the parts descriptions use ---------------------------------------------------

_INLINE = [
    (re.compile(r"``(.+?)``"), r"<code>\1</code>"),
    (re.compile(r":[\w:.-]+:`~?([^`<]+?)(?: <[^>]+>)?`"), r"<code>\1</code>"),  # :class:`x`, :data:`~a.b`
    (re.compile(r"`([^`<]+?) <([^>]+)>`_{1,2}"), r"<a href='\2'>\1</a>"),
    (re.compile(r"`([^`]+?)`_{0,2}"), r"<code>\1</code>"),
    (re.compile(r"\*\*(.+?)\*\*"), r"<b>\1</b>"),
    (re.compile(r"(?<![\w*])\*([^*\s][^*]*?)\*(?![\w*])"), r"<i>\1</i>"),
]


def rst_inline(text: str) -> str:
    """One line of reStructuredText inline markup as HTML (escaped; ``~a.b`` shows ``a.b``).

    Examples
    --------
    >>> rst_inline("the ``pokeys.x.step`` train (:class:`cosim.trace.Trace`), *not* **this** <b>")
    'the <code>pokeys.x.step</code> train (<code>cosim.trace.Trace</code>), <i>not</i> <b>this</b> &lt;b&gt;'
    """
    out = html.escape(text, quote=False)
    for pattern, replacement in _INLINE:
        out = pattern.sub(replacement, out)
    return out


def rst_html(text: str) -> str:
    """A description in reStructuredText as HTML: paragraphs, bullet and numbered lists, literal blocks
    (after ``::``, or ``>>>`` examples), headings underlined with ``=-~``, inline markup.

    Examples
    --------
    >>> rst_html("A *b*::\\n\\n    code here\\n\\n* one\\n* two ``x``")
    "<p>A <i>b</i>:</p><pre class='doc'>code here</pre><ul><li>one</li><li>two <code>x</code></li></ul>"
    """
    lines = text.expandtabs().splitlines()
    out: list[str] = []
    para: list[str] = []
    items: list[str] = []
    ordered = False
    literal_next = False
    k = 0

    def flush() -> None:
        nonlocal para, items
        if para:
            out.append(f"<p>{rst_inline(' '.join(para))}</p>")
            para = []
        if items:
            tag = "ol" if ordered else "ul"
            out.append(f"<{tag}>" + "".join(f"<li>{rst_inline(i)}</li>" for i in items) + f"</{tag}>")
            items = []

    while k < len(lines):
        line = lines[k]
        stripped = line.strip()
        indent = len(line) - len(line.lstrip())
        if not stripped:
            flush()
            k += 1
            continue
        if (literal_next and indent > 0) or stripped.startswith(">>>"):
            flush()
            block, base = [], indent
            while k < len(lines) and (not lines[k].strip() or len(lines[k]) - len(lines[k].lstrip()) >= base
                                      or lines[k].strip().startswith((">>>", "..."))):
                if not lines[k].strip() and stripped.startswith(">>>"):
                    break
                block.append(lines[k][base:] if len(lines[k]) >= base else "")
                k += 1
            out.append(f"<pre class='doc'>{html.escape(chr(10).join(block).rstrip())}</pre>")
            literal_next = False
            continue
        literal_next = False
        if k + 1 < len(lines) and re.fullmatch(r"([=~\-^])\1{2,}", lines[k + 1].strip()) \
                and len(lines[k + 1].strip()) >= len(stripped) > 0:
            flush()
            out.append(f"<h3>{rst_inline(stripped)}</h3>")
            k += 2
            continue
        bullet = re.match(r"^([*+-]|\d+[.)]|#\.)\s+(.*)$", stripped)
        if bullet and indent <= 2:
            if para:
                flush()
            ordered = bullet[1] not in "*+-"
            items.append(bullet[2])
        elif items and indent > 0:
            items[-1] += " " + stripped
        else:
            if items:
                flush()
            para.append(stripped)
        if stripped.endswith("::"):
            target = items if items and not para else para
            target[-1] = target[-1][:-2].rstrip() + (":" if not target[-1][:-2].rstrip().endswith(":") else "")
            if target[-1] == ":":
                target.pop()
            literal_next = True
            flush()
        k += 1
    flush()
    return "".join(out)
