"""``PRINT``, ``INPUT``, ``GET`` and ``LINPUT``: compiled to operations on the program's channels.

``PRINT [#channel,] item; item, item`` writes one console line (``;`` joins, ``,`` puts a tab, a
trailing ``;`` or ``,`` keeps the line open for the next PRINT). A number is shown with four decimal
places; ``value[w, d]`` right-aligns it in ``w`` characters with ``d`` decimals and ``value[d]``
shows ``d`` decimals [?: the one-number form is read as the decimals]. Strings (``"text"``,
``CHR(13)``, ``HEX(x)``, ``STR(x)``, string variables) are shown as they are.

``INPUT [#channel,] ["prompt",] var, ...`` waits for a line on the channel for each variable and
reads the number at its start; ``GET [#channel,] var`` waits for one character and stores its code;
``LINPUT [#channel,] VR(n)`` stores a line's character codes in ``VR(n)``, ``VR(n+1)``... ending
with 13. A channel is fed by the machine file (``[[channel]]``) or by
:meth:`~cosim.controllers.trio.controller.TrioController.channel` from a scenario. The default
channel is the process' ``INDEVICE`` / ``OUTDEVICE`` (0).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

from lark import Token, Tree

from cosim.controllers.trio import keywords as kw
from cosim.controllers.trio.runtime import BasicError, store_variable
from cosim.controllers.trio.values import Datum, formatted, integer_part, number, parse_number, to_text

if TYPE_CHECKING:
    from cosim.controllers.trio.compiler import Compiler
    from cosim.controllers.trio.runtime import BasicRun

Part = Callable[["BasicRun"], str]


def _channel(compiler: Compiler, node: Tree | None) -> Callable[[BasicRun], int | None]:
    if node is None:
        return lambda run: None
    value = compiler.expr(node.children[0], 0)

    def channel(run: BasicRun) -> int:
        n = integer_part(number(value(run), "channel"))
        if not 0 <= n <= 255:
            raise BasicError(f"channel = {n} is not allowed (allowed: 0..255)", 1)
        return n
    return channel


def _shown(value: Datum) -> str:
    return value if isinstance(value, str) else to_text(value)


def _item(compiler: Compiler, node: Tree) -> Part:
    expr_node, format_node = node.children
    value = compiler.expr(expr_node, 0)
    if format_node is None:
        return lambda run: _shown(value(run))
    first, second = format_node.children
    width_expr = compiler.expr(first, 0)
    decimals_expr = compiler.expr(second, 0) if second is not None else None

    def show(run: BasicRun) -> str:
        datum = value(run)
        if isinstance(datum, str):
            return datum
        a = integer_part(number(width_expr(run), "PRINT width"))
        if decimals_expr is None:
            width, decimals = 0, a
        else:
            width, decimals = a, integer_part(number(decimals_expr(run), "PRINT decimals"))
        if not 0 <= decimals <= 9 or not 0 <= width <= 255:
            raise BasicError(f"PRINT format [{width}, {decimals}] is not allowed (allowed: width 0..255, "
                             "decimals 0..9)", 1)
        return formatted(datum, width, decimals)
    return show


def compile_print(compiler: Compiler, node: Tree) -> None:
    channel_node, *rest = node.children
    channel = _channel(compiler, channel_node)
    parts: list[Part] = []
    ends_line = True
    for child in rest:
        if child is None:
            continue
        if child.data == "print_item":
            parts.append(_item(compiler, child))
            ends_line = True
        else:
            if child.data == "comma_sep":
                parts.append(lambda run: "\t")
            ends_line = False

    def print_line(run: BasicRun, pc: int) -> int:
        ch = channel(run)
        run.print_text("".join(part(run) for part in parts), end=ends_line,
                       channel=run.outdevice if ch is None else ch)
        return pc + 1

    compiler.emit(node, print_line)


def compile_input(compiler: Compiler, node: Tree, kind: str) -> None:
    channel_node, *rest = node.children
    channel = _channel(compiler, channel_node)
    prompt = None
    if kind == "INPUT" and rest and (rest[0] is None or isinstance(rest[0], Token)):
        token = rest.pop(0)
        prompt = None if token is None else str(token)[1:-1]
    targets = [t for t in rest if t is not None]
    stores = [_target(compiler, t, kind) for t in targets]

    def read(run: BasicRun, pc: int) -> int:
        ch = channel(run)
        port = run.controller.channel(run.indevice if ch is None else ch)
        step = run.input_step  # which target of this statement is next (0 when it starts)
        if step == 0 and prompt is not None and not run.input_prompted:
            run.print_text(prompt, end=False)
            run.input_prompted = True
        while step < len(stores):
            if kind == "GET":
                code = port.read_char()
                value: Datum | None = code
            elif kind == "LINPUT":
                line = port.read_line()
                value = line
            else:
                line = port.read_line()
                value = None if line is None else parse_number(line)
            if value is None:
                run.input_step = step
                run.pending = port.arrival()
                return pc  # waits for the channel, then reads again
            stores[step](run, value)
            step += 1
        run.input_step, run.input_prompted = 0, False
        return pc + 1

    compiler.emit(node, read)


def _target(compiler: Compiler, node: Tree, kind: str) -> Callable[[BasicRun, Datum], None]:
    token, index_node = node.children
    assert isinstance(token, Token)
    name = str(token).upper()
    if kind == "LINPUT":
        if name != "VR" or index_node is None:
            raise compiler.fail(token, "LINPUT stores a line in VRs: write LINPUT #channel, VR(n)")
        first = compiler.expr(index_node.children[0], 0)

        def store_line(run: BasicRun, line: Datum) -> None:
            start = integer_part(number(first(run), "VR index"))
            for k, char in enumerate(str(line)):
                run.controller.set_vr(start + k, ord(char))
            run.controller.set_vr(start + len(str(line)), 13)
        return store_line
    if index_node is not None:
        index_args = [a for a in index_node.children if a is not None]
        if name == "VR" and len(index_args) == 1:
            index = compiler.expr(index_args[0], 0)
            return lambda run, value: run.controller.set_vr(index(run), value)
        if name in compiler.arrays:
            element = compiler.index(name, [compiler.expr(a, 1) for a in index_args])

            def store_element(run: BasicRun, value: Datum) -> None:
                k = element(run)  # first: it checks that the DIM has run
                run.arrays[name][k] = value
            return store_element
        raise compiler.fail(token, f"{kind} stores in a variable, VR(n) or a DIM'd array element, not {token}(...)")
    if name in compiler.declarations.globals:
        slot = compiler.declarations.globals[name]
        return lambda run, value: run.controller.set_vr(slot, value)
    if name in kw.KEYWORDS or name in compiler.declarations.constants:
        raise compiler.fail(token, f"{kind} stores in a variable, not in {name}")
    compiler.assigned.setdefault(name, (token.line or 0, token.column or 0))
    return lambda run, value: store_variable(run, name, value)
