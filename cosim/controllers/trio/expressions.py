"""Compiling Trio BASIC expressions and names (part of :mod:`.compiler`).

A name in an expression is, in this order: a ``CONSTANT``, a ``GLOBAL`` (an alias of ``VR(n)``), a
BASIC constant (``ON``, ``TRUE``...), a parameter (axis, process, system; with ``AXIS(n)`` or
``PROC(n)``), a ``DIM``'d array (with an index) or a local variable (created on first assignment).
Expressions become closures ``expr(run) -> value``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from lark import Token, Tree

from cosim.controllers.trio import keywords as kw
from cosim.controllers.trio import operations as ops
from cosim.controllers.trio.functions import FUNCTIONS, pi
from cosim.controllers.trio.runtime import BasicError
from cosim.controllers.trio.values import Datum, fit, hex_literal, integer_part, literal, number
from cosim.errors import ConfigurationError

if TYPE_CHECKING:
    from cosim.controllers.trio.runtime import BasicRun

Expr = ops.Expr
#: Deepest nesting of blocks (IF, loops) and of expressions.
MAX_NESTING = 64


@dataclass
class Declarations:
    """``CONSTANT`` and ``GLOBAL`` names, shared by the programs of one machine (as on the controller, where
    a name declared by one program is known to every program after it).

    Parameters
    ----------
    constants : dict
        Name -> value.
    globals : dict
        Name -> VR index.
    """

    constants: dict[str, Datum] = field(default_factory=dict)
    globals: dict[str, int] = field(default_factory=dict)


def pos(node: Tree | Token) -> tuple[int, int]:
    if isinstance(node, Token):
        return node.line or 0, node.column or 0
    return (node.meta.line, node.meta.column) if not node.meta.empty else (0, 0)


def _mods(node: Tree | None) -> tuple[Tree | None, Tree | None]:
    """The ``AXIS(n)`` and ``PROC(n)`` modifiers of a ``mods`` node."""
    axis = proc = None
    if node is not None:
        for child in node.children:
            if child.data == "axis_mod":
                axis = child
            else:
                proc = child
    return axis, proc


class ExpressionCompiler:
    """Names and expressions (the statements are in :class:`~.compiler.Compiler`)."""

    name: str
    declarations: Declarations
    arrays: dict[str, int]
    typed: set[str]
    assigned: dict[str, tuple[int, int]]
    read: dict[str, tuple[int, int]]
    inputs: set[int]

    def fail(self, node: Tree | Token, message: str) -> ConfigurationError:
        line, column = pos(node)
        return ConfigurationError(f"{self.name} line {line}, column {column}: {message}")

    def axis(self, axis_mod: Tree | None) -> Callable[[BasicRun], Any]:
        if axis_mod is None:
            return lambda run: None
        value = self.expr(axis_mod.children[0], 0)
        return lambda run: number(value(run), "AXIS")

    def proc(self, proc_mod: Tree | None) -> Callable[[BasicRun], Any]:
        if proc_mod is None:
            return lambda run: None
        value = self.expr(proc_mod.children[0], 0)
        return lambda run: number(value(run), "PROC")

    def literal_channel(self, node: Any, into: set[int]) -> None:
        if isinstance(node, Tree) and node.data == "number":
            value = literal(str(node.children[0]))
            if isinstance(value, int) and 0 <= value < 64:
                into.add(value)

    def constant_value(self, node: Tree, what: str) -> Datum:
        """An expression's value known before the program runs (numbers, strings, CONSTANTs)."""
        expr = self.expr(node, 0)
        try:
            return expr(None)  # type: ignore[arg-type]
        except (AttributeError, TypeError):
            raise self.fail(node, f"{what} must be known before the program runs (numbers, strings and "
                                  "CONSTANTs)") from None
        except ConfigurationError as exc:
            raise self.fail(node, str(exc)) from None

    def expr(self, node: Tree | Token, depth: int) -> Expr:
        if depth > MAX_NESTING:
            raise self.fail(node, f"expression nested deeper than {MAX_NESTING} levels")
        if isinstance(node, Token):  # pragma: no cover - every token is wrapped in a rule
            raise self.fail(node, f"cannot evaluate {node!r}")
        kind, kids = node.data, node.children
        if kind in ("number", "hexnumber"):
            try:
                value = literal(str(kids[0])) if kind == "number" else hex_literal(str(kids[0]))
            except ConfigurationError as exc:
                raise self.fail(node, str(exc)) from None
            return ops.constant(value)
        if kind == "string":
            return ops.constant(str(kids[0])[1:-1])
        if kind == "on_const":
            if kids[0] is not None and kids[0].children:
                raise self.fail(node, "ON is a constant; it takes no AXIS() or PROC()")
            return ops.constant(kw.CONSTANTS["ON"])
        if kind == "ref":
            return self.ref(node)
        if kind in ("idle_ref", "loaded_ref"):
            key = "IDLE" if kind == "idle_ref" else "LOADED"
            axis_mod, proc_mod = _mods(kids[0])
            if proc_mod is not None:
                raise self.fail(proc_mod, f"{key} is an axis parameter; it takes AXIS(), not PROC()")
            axis = self.axis(axis_mod)
            return lambda run: fit(run.process.get(key, axis=axis(run)))
        if kind == "func":
            return self.function(node, depth)
        if kind == "channel_func":
            return self.channel_function(node, depth)
        if kind in ("sum", "term", "or_expr", "and_expr", "pow_expr"):
            first = self.expr(kids[0], depth + 1)
            rest = [(ops.BINARY[str(kids[k]).upper()], self.expr(kids[k + 1], depth + 1))
                    for k in range(1, len(kids), 2)]
            return ops.chain(first, rest)
        if kind in ("compare", "equal"):
            a = self.expr(kids[0], depth + 1)
            b = self.expr(kids[-1], depth + 1)
            op = ops.BINARY[str(kids[1]) if kind == "compare" else "="]
            return lambda run: op(a(run), b(run))
        operand = self.expr(kids[0], depth + 1)
        if kind == "neg":
            return ops.negate(operand)
        if kind == "not_op":
            return ops.logical_not(operand)
        raise self.fail(node, f"cannot evaluate {kind}")  # pragma: no cover - the grammar has no other rules

    def memory_only(self, node: Tree | Token) -> bool:
        """The expression (compiled already) reads only memory: numbers, constants, VR (also by a GLOBAL name),
        TABLE, the program's own variables and arrays; no parameter, input, time or other function."""
        if isinstance(node, Token):
            return True  # an operator
        kind, kids = node.data, node.children
        if kind in ("number", "hexnumber", "string", "on_const"):
            return True
        if kind == "ref":
            token, mods = kids
            name = str(token).upper()
            if mods is not None and mods.children:
                return False
            declared = self.declarations
            return (name in declared.constants or name in kw.CONSTANTS or name == "PI" or name in declared.globals
                    or not (name in kw.PROCESS_PARAMS or name in kw.READABLE or name in kw.FUNCTIONS
                            or name in kw.KEYWORDS))
        if kind == "func":
            token, *args, mods = kids
            name = str(token).upper()
            if (mods is not None and mods.children) or not (
                    name in ("VR", "TABLE") or (name in self.arrays and name not in kw.FUNCTIONS)):
                return False
            return all(a is None or self.memory_only(a) for a in args)
        if kind in ("sum", "term", "or_expr", "and_expr", "pow_expr", "compare", "equal", "neg", "not_op"):
            return all(self.memory_only(k) for k in kids)
        return False

    def ref(self, node: Tree) -> Expr:
        token, mods = node.children
        name = str(token).upper()
        axis_mod, proc_mod = _mods(mods)
        declared = self.declarations
        if name in declared.constants or name in kw.CONSTANTS or name == "PI":
            for mod in (axis_mod, proc_mod):
                if mod is not None:
                    raise self.fail(token, f"{name} is a constant; it takes no AXIS() or PROC()")
            value = pi() if name == "PI" else declared.constants.get(name, kw.CONSTANTS.get(name))
            return ops.constant(value)  # type: ignore[arg-type]
        if name in declared.globals:
            index = declared.globals[name]
            return lambda run: run.controller.vr(index)
        if name in kw.PROCESS_PARAMS:
            if axis_mod is not None:
                raise self.fail(token, f"{name} is a process parameter; it takes PROC(n), not AXIS()")
            proc = self.proc(proc_mod)
            return lambda run: run.program_control.process_param(run, name, proc(run))
        if name in kw.READABLE:
            if proc_mod is not None:
                raise self.fail(proc_mod, f"{name} is not a process parameter; it takes no PROC()")
            axis = self.axis(axis_mod)
            return lambda run: fit(run.process.get(name, axis=axis(run)), name)
        if name in kw.FUNCTIONS and kw.FUNCTIONS[name].low == 0:
            return self.call_function(node, name, [], axis_mod, proc_mod, 0)
        if name in kw.KEYWORDS:
            raise self.fail(token, kw.misplaced(name, "value") or f"{name} is not a value here" + (
                f"; write {kw.FUNCTIONS[name].usage}" if name in kw.FUNCTIONS else ""))
        if axis_mod is not None or proc_mod is not None:
            raise self.fail(token, kw.unknown_name(name) + " (AXIS() and PROC() only modify parameters)")
        if name in self.arrays:
            raise self.fail(token, f"{name} is an array; read an element with {name}(index)")
        self.read.setdefault(name, pos(token))
        return lambda run: run.variable(name)

    def function(self, node: Tree, depth: int) -> Expr:
        token, *args, mods = node.children
        args = [a for a in args if a is not None]
        name = str(token).upper()
        axis_mod, proc_mod = _mods(mods)
        if name in self.arrays and name not in kw.FUNCTIONS:
            if axis_mod is not None or proc_mod is not None:
                raise self.fail(token, f"{name} is an array; it takes no AXIS() or PROC()")
            return self.element(node, name, args)
        if name not in kw.FUNCTIONS:
            if name in kw.ALL_COMMANDS:
                raise self.fail(token, f"{name}(...) is a command, not a function")
            if name in kw.READABLE or name in self.declarations.globals or name in self.declarations.constants:
                raise self.fail(token, f"{name} is a value, not a function (write {name} without parentheses, or "
                                       f"{name} AXIS(n))")
            raise self.fail(token, kw.misplaced(name, "function") or kw.unknown_function(str(token)))
        return self.call_function(token, name, args, axis_mod, proc_mod, depth)

    def channel_function(self, node: Tree, depth: int) -> Expr:
        """``KEY #channel``: a function of a channel (TRM: KEY #n is TRUE while channel n has a character)."""
        token, channel_node = node.children
        name = str(token).upper()
        if name not in kw.CHANNEL_FUNCTIONS:
            raise self.fail(token, f"{name} #channel is not a function of a channel (allowed: "
                                   f"{', '.join(f'{n} #channel' for n in sorted(kw.CHANNEL_FUNCTIONS))})")
        channel = self.expr(channel_node, depth + 1)
        function = FUNCTIONS[name]
        return lambda run: function(run, channel(run))

    def call_function(self, node: Tree | Token, name: str, args: list[Any], axis_mod: Tree | None,
                      proc_mod: Tree | None, depth: int) -> Expr:
        signature = kw.FUNCTIONS[name]
        if not signature.accepts(len(args)):
            raise self.fail(node, kw.wrong_count(signature, len(args)))
        for mod in (axis_mod, proc_mod):
            if mod is not None:
                raise self.fail(mod, f"{name} takes no AXIS() or PROC() modifier")
        values = [self.expr(a, depth + 1) for a in args]
        if name == "IN" and args:
            self.literal_channel(args[0], self.inputs)
        function = FUNCTIONS[name]
        if len(values) == 1:
            (one,) = values
            return lambda run: function(run, one(run))
        return lambda run: function(run, *(v(run) for v in values))

    def element(self, node: Tree, name: str, args: list[Any]) -> Expr:
        dims = self.arrays[name]
        if len(args) != dims:
            raise self.fail(node, f"{name} has {dims} dimension{'s' if dims > 1 else ''}; {len(args)} "
                                  f"ind{'ices' if len(args) != 1 else 'ex'} given")
        index = self.index(name, [self.expr(a, 1) for a in args])

        def load(run: BasicRun) -> Datum:
            k = index(run)  # first: it checks that the DIM has run
            return run.arrays[name][k]
        return load

    def index(self, name: str, values: list[Expr]) -> Callable[[BasicRun], int]:
        """The flat index of an element of array ``name`` (checked against its size at run time)."""
        def flat(run: BasicRun) -> int:
            sizes = run.array_sizes.get(name)
            if sizes is None:
                raise BasicError(f"array {name} is used before its DIM runs", 4)
            k = 0
            for size, value in zip(sizes, values, strict=True):
                i = integer_part(number(value(run), f"{name} index"))
                if not 0 <= i < size:
                    raise BasicError(f"{name} index = {i} is not allowed (allowed: 0..{size - 1})", 4)
                k = k * size + i
            return k
        return flat
