"""Check a parsed Trio BASIC program and compile it into a flat list of operations.

Every check that does not need the machine is made here, before anything runs, and names the
program, the line and the column: an unknown keyword (with close matches and the supported ones),
a wrong number of arguments (with the allowed count), a label used but not defined or defined
twice, ``NEXT`` naming another loop, a one-line ``IF`` followed on its line by another statement,
a number literal beyond what a variable holds, nesting deeper than :data:`MAX_NESTING`, a variable
read but never assigned or assigned but never read (how a misspelt parameter shows up).

The program becomes a list of operations ``op(run, pc) -> next pc``; loops, ``IF``, ``GOTO`` and
``GOSUB`` are jumps, so running a program needs no recursion and any jump is possible.
Expressions become closures ``expr(run) -> value``; each arithmetic result is kept in the variable
format (:func:`~cosim.controllers.trio.values.fit`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from lark import Token, Tree

from cosim.controllers.trio import keywords as kw
from cosim.controllers.trio import operations as ops
from cosim.controllers.trio.values import Value, fit, hex_literal, integer_part, literal
from cosim.errors import ConfigurationError

if TYPE_CHECKING:
    from cosim.controllers.trio.basic import BasicRun

Op = ops.Op
Expr = ops.Expr
#: Deepest nesting of blocks (IF, loops) and of expressions.
MAX_NESTING = 64
#: Arguments PWM_CONTROL takes after the mode, by mode (TN20-81).
PWM_CONTROL_ARGS = {0: 0, 1: 0, 2: 4, 3: 4, 4: 0, 5: 0, 6: 0}


@dataclass(frozen=True)
class Compiled:
    """A compiled program: operations, the program line of each, and the channels it names."""

    ops: tuple[Op, ...]
    lines: tuple[int, ...]
    inputs: frozenset[int]
    outputs: frozenset[int]


def _pos(node: Tree | Token) -> tuple[int, int]:
    if isinstance(node, Token):
        return node.line or 0, node.column or 0
    return (node.meta.line, node.meta.column) if not node.meta.empty else (0, 0)


class Compiler:
    """Checks and compiles one program (see the module docstring)."""

    def __init__(self, name: str) -> None:
        self.name = name
        self.ops: list[Op] = []
        self.lines: list[int] = []
        self.labels: dict[str, int] = {}
        self.jumps: list[tuple[int, str, Tree | Token, bool]] = []  # (op index, label, node, gosub)
        self.assigned: dict[str, tuple[int, int]] = {}
        self.read: dict[str, tuple[int, int]] = {}
        self.inputs: set[int] = set()
        self.outputs: set[int] = set()

    def fail(self, node: Tree | Token, message: str) -> ConfigurationError:
        line, column = _pos(node)
        return ConfigurationError(f"{self.name} line {line}, column {column}: {message}")

    def compile(self, tree: Tree) -> Compiled:
        self.block(tree, 0)
        for index, label, node, gosub in self.jumps:
            if label not in self.labels:
                known = ", ".join(sorted(self.labels)) or "none"
                raise self.fail(node, f"label {label} is not defined (labels: {known})")
            self.ops[index] = ops.gosub(self.labels[label]) if gosub else ops.jump(self.labels[label])
        for var, (line, column) in self.read.items():
            if var not in self.assigned:
                raise ConfigurationError(f"{self.name} line {line}, column {column}: {kw.unknown_name(var)} (not a "
                                         "keyword, nor a variable the program assigns)")
        for var, (line, column) in self.assigned.items():
            if var not in self.read:
                raise ConfigurationError(f"{self.name} line {line}, column {column}: {kw.unknown_name(var)} "
                                         "(assigned but never read: a misspelt keyword?)")
        return Compiled(tuple(self.ops), tuple(self.lines), frozenset(self.inputs), frozenset(self.outputs))

    def emit(self, node: Tree | Token, op: Op) -> int:
        self.ops.append(op)
        self.lines.append(_pos(node)[0])
        return len(self.ops) - 1

    # -- statements ---------------------------------------------------------------------------
    def block(self, tree: Tree, depth: int) -> None:
        if depth > MAX_NESTING:
            raise self.fail(tree, f"blocks nested deeper than {MAX_NESTING} levels")
        nodes = [c for c in tree.children if isinstance(c, Tree)]
        for k, node in enumerate(nodes):
            if node.data == "if_line" and k + 1 < len(nodes) and _pos(nodes[k + 1])[0] == node.meta.end_line:
                raise self.fail(nodes[k + 1], "a one-line IF governs one statement; this one would run whatever "
                                              "the condition (write IF ... THEN, the statements, ENDIF)")
            self.statement(node, depth)

    def statement(self, node: Tree, depth: int) -> None:
        handler = getattr(self, f"s_{node.data}")
        handler(node, depth)

    def s_label(self, node: Tree, depth: int) -> None:
        token = node.children[0]
        name = str(token).rstrip(": \t").upper()
        if name in kw.KEYWORDS:
            raise self.fail(token, f"{name} is a keyword, not a label (remove the colon)")
        if name in self.labels:
            raise self.fail(token, f"label {name} is defined twice")
        self.labels[name] = len(self.ops)

    def s_assign(self, node: Tree, depth: int) -> None:
        token, axis_mod, value_node = node.children
        name = str(token).upper()
        value = self.expr(value_node, 0)
        if name in kw.WRITABLE:
            if axis_mod is not None and name in ("WDOG", "TICKS"):
                raise self.fail(token, f"{name} is not an axis parameter; write {name} = value without AXIS()")
            if name == "TICKS":
                self.emit(node, ops.action(lambda run: setattr(run.process, "ticks", value(run))))
                return
            axis = self.axis(axis_mod)
            self.emit(node, ops.action(lambda run: run.process.set(name, value(run), axis=axis(run))))
            return
        if name in kw.READABLE:
            hint = " (use DEFPOS)" if name in ("DPOS", "MPOS") else ""
            raise self.fail(token, f"{name} is read-only{hint}")
        if name in kw.KEYWORDS:
            raise self.fail(token, f"cannot assign to {name}")
        if axis_mod is not None:
            raise self.fail(token, kw.unknown_name(name) + " (AXIS() only modifies axis parameters)")
        self.assigned.setdefault(name, _pos(token))

        def assign(run: BasicRun, pc: int) -> int:
            run.variables[name] = value(run)
            return pc + 1

        self.emit(node, assign)

    def s_index_assign(self, node: Tree, depth: int) -> None:
        token, *args, value_node = node.children
        name = str(token).upper()
        if name != "VR":
            raise self.fail(token, f"cannot assign to {token}(...); write VR(n) = value or TABLE(n, value)")
        if len(args) != 1:
            raise self.fail(token, kw.wrong_count(kw.FUNCTIONS["VR"], len(args)))
        index, value = self.expr(args[0], 0), self.expr(value_node, 0)
        self.emit(node, ops.action(lambda run: run.controller.set_vr(index(run), value(run))))

    def s_call(self, node: Tree, depth: int) -> None:
        token, *args, axis_mod = node.children
        args = [a for a in args if a is not None]
        name = str(token).upper()
        if name not in kw.COMMANDS:
            if name in kw.FUNCTIONS:
                raise self.fail(token, f"{name}(...) is a function, not a command; use it in an expression")
            raise self.fail(token, kw.unknown_command(str(token)))
        self.command(node, kw.COMMANDS[name], args, axis_mod)

    def s_bare(self, node: Tree, depth: int) -> None:
        token, axis_mod = node.children
        name = str(token).upper()
        if name in kw.COMMANDS:
            signature = kw.COMMANDS[name]
            if signature.low:
                raise self.fail(token, f"{name} needs its arguments: {signature.usage}")
            self.command(node, signature, [], axis_mod)
        elif name in kw.READABLE:
            raise self.fail(token, f"{name} is a parameter; write {name} = value")
        else:
            raise self.fail(token, kw.unknown_command(str(token)))

    def command(self, node: Tree, signature: kw.Signature, args: list[Any], axis_mod: Tree | None) -> None:
        name = signature.name
        if not signature.accepts(len(args)):
            raise self.fail(node, kw.wrong_count(signature, len(args)))
        if axis_mod is not None and not signature.axis_modifier:
            raise self.fail(axis_mod, f"{name} takes no AXIS() modifier")
        values = [self.expr(a, 0) for a in args]
        axis = self.axis(axis_mod)
        if name == "PWM_CONTROL" and isinstance(args[0], Tree) and args[0].data == "number":
            mode = literal(str(args[0].children[0]))
            if isinstance(mode, int) and mode in PWM_CONTROL_ARGS and len(args) - 1 != PWM_CONTROL_ARGS[mode]:
                wanted = PWM_CONTROL_ARGS[mode] + 1
                raise self.fail(node, f"number of PWM_CONTROL({mode}) arguments = {len(args)} is not allowed "
                                      f"(allowed: {wanted}, the mode and {wanted - 1} more)")
        if name == "OP":
            self._literal_channel(args[0], self.outputs)
        self.emit(node, ops.command(name, values, axis))

    def s_wait_idle(self, node: Tree, depth: int) -> None:
        axis = self.axis(node.children[0])
        self.emit(node, ops.wait(lambda run: run.process.wait_idle(axis=axis(run))))

    def s_wait_loaded(self, node: Tree, depth: int) -> None:
        axis = self.axis(node.children[0])
        self.emit(node, ops.wait(lambda run: run.process.wait_loaded(axis=axis(run))))

    def s_wait_until(self, node: Tree, depth: int) -> None:
        condition = self.expr(node.children[0], 0)

        def wait_until(run: BasicRun, pc: int) -> int:
            if condition(run) != 0:
                return pc + 1
            run.pending = run.next_servo_tick()
            return pc  # checked again at the next servo tick

        self.emit(node, wait_until)

    def s_goto(self, node: Tree, depth: int) -> None:
        self.jumps.append((self.emit(node, ops.jump(-1)), str(node.children[0]).upper(), node.children[0], False))

    def s_gosub(self, node: Tree, depth: int) -> None:
        self.jumps.append((self.emit(node, ops.jump(-1)), str(node.children[0]).upper(), node.children[0], True))

    def s_return_stmt(self, node: Tree, depth: int) -> None:
        self.emit(node, lambda run, pc: run.return_from_gosub())

    def s_print_stmt(self, node: Tree, depth: int) -> None:
        parts: list[Callable[[BasicRun], str]] = []
        ends_line = True
        for child in node.children:
            if child is None:
                continue
            if child.data == "print_item":
                item = child.children[0]
                if isinstance(item, Token) and item.type == "STRING":
                    parts.append(ops.text(str(item)[1:-1]))
                else:
                    parts.append(ops.formatted(self.expr(item, 0)))
                ends_line = True
            else:
                if child.data == "comma_sep":
                    parts.append(lambda run: "\t")
                ends_line = False

        def print_line(run: BasicRun, pc: int) -> int:
            run.print_text("".join(part(run) for part in parts), end=ends_line)
            return pc + 1

        self.emit(node, print_line)

    def s_run_stmt(self, node: Tree, depth: int) -> None:
        token, process_node = node.children
        program = str(token)[1:-1]
        process = None if process_node is None else self.expr(process_node, 0)
        self.emit(node, ops.action(lambda run: run.run_program(program, None if process is None else process(run))))

    def s_repeat(self, node: Tree, depth: int) -> None:
        body, condition_node = node.children
        start = len(self.ops)
        self.block(body, depth + 1)
        condition = self.expr(condition_node, 0)
        self.emit(condition_node, lambda run, pc: pc + 1 if condition(run) != 0 else start)

    def s_while_loop(self, node: Tree, depth: int) -> None:
        condition_node, body = node.children
        condition = self.expr(condition_node, 0)
        top = self.emit(node, ops.jump(-1))
        self.block(body, depth + 1)
        self.emit(node, ops.jump(top))
        end = len(self.ops)
        self.ops[top] = lambda run, pc: pc + 1 if condition(run) != 0 else end

    def s_for_loop(self, node: Tree, depth: int) -> None:
        token, start_node, stop_node, step_node, body, next_token = node.children
        var = str(token).upper()
        if next_token is not None and str(next_token).upper() != var:
            raise self.fail(next_token, f"NEXT {next_token} closes FOR {token}")
        if var in kw.KEYWORDS:
            raise self.fail(token, f"cannot use {var} as a loop variable")
        self.assigned.setdefault(var, _pos(token))
        self.read.setdefault(var, _pos(token))
        start, stop = self.expr(start_node, 0), self.expr(stop_node, 0)
        step = (lambda run: 1) if step_node is None else self.expr(step_node, 0)
        init = self.emit(node, ops.jump(-1))
        self.block(body, depth + 1)
        next_op = self.emit(next_token if next_token is not None else body if not body.meta.empty else node,
                            ops.for_next(var, init, init + 1))
        self.ops[init] = ops.for_init(var, start, stop, step, next_op + 1)

    def s_if_block(self, node: Tree, depth: int) -> None:
        condition_node, then_body, *rest = node.children
        else_body = rest.pop() if rest and (rest[-1] is None or rest[-1].data == "body") else None
        branches = [(condition_node, then_body)] + [(e.children[0], e.children[1]) for e in rest]
        ends: list[int] = []
        for cond_node, body in branches:
            condition = self.expr(cond_node, 0)
            test = self.emit(cond_node, ops.jump(-1))
            self.block(body, depth + 1)
            ends.append(self.emit(node, ops.jump(-1)))
            skip_to = len(self.ops)
            self.ops[test] = ops.jump_unless(condition, skip_to)
        if else_body is not None:
            self.block(else_body, depth + 1)
        end = len(self.ops)
        for index in ends:
            self.ops[index] = ops.jump(end)

    def s_if_line(self, node: Tree, depth: int) -> None:
        condition_node, then_stmt, *rest = node.children  # lark adds no placeholder for a missing ELSE here
        else_stmt = rest[0] if rest else None
        condition = self.expr(condition_node, 0)
        test = self.emit(condition_node, ops.jump(-1))
        self.statement(then_stmt, depth + 1)
        if else_stmt is None:
            self.ops[test] = ops.jump_unless(condition, len(self.ops))
            return
        skip = self.emit(node, ops.jump(-1))
        self.ops[test] = ops.jump_unless(condition, len(self.ops))
        self.statement(else_stmt, depth + 1)
        self.ops[skip] = ops.jump(len(self.ops))

    # -- expressions --------------------------------------------------------------------------
    def axis(self, axis_mod: Tree | None) -> Callable[[BasicRun], Value | None]:
        if axis_mod is None:
            return lambda run: None
        return self.expr(axis_mod.children[0], 0)

    def _literal_channel(self, node: Any, into: set[int]) -> None:
        if isinstance(node, Tree) and node.data == "number":
            value = literal(str(node.children[0]))
            if isinstance(value, int) and 0 <= value < 64:
                into.add(value)

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
            return lambda run: value
        if kind == "ref":
            return self.ref(node)
        if kind in ("idle_ref", "loaded_ref"):
            key = "IDLE" if kind == "idle_ref" else "LOADED"
            axis = self.axis(kids[0])
            return lambda run: fit(run.process.get(key, axis=axis(run)))
        if kind == "func":
            return self.function(node, depth)
        if kind in ("sum", "term", "or_expr", "and_expr"):
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
            return lambda run: fit(-operand(run))
        if kind == "not_op":
            return lambda run: ~integer_part(operand(run))
        raise self.fail(node, f"cannot evaluate {kind}")  # pragma: no cover - the grammar has no other rules

    def ref(self, node: Tree) -> Expr:
        token, axis_mod = node.children
        name = str(token).upper()
        if name in kw.CONSTANTS:
            if axis_mod is not None:
                raise self.fail(token, f"{name} is a constant; it takes no AXIS()")
            value = kw.CONSTANTS[name]
            return lambda run: value
        if name == "TICKS":
            return lambda run: run.process.ticks
        if name in kw.READABLE:
            axis = self.axis(axis_mod)
            return lambda run: fit(run.process.get(name, axis=axis(run)), name)
        if name in kw.KEYWORDS:
            raise self.fail(token, f"{name} is not a value here" + (
                f"; write {kw.FUNCTIONS[name].usage}" if name in kw.FUNCTIONS else ""))
        if axis_mod is not None:
            raise self.fail(token, kw.unknown_name(name) + " (AXIS() only modifies axis parameters)")
        self.read.setdefault(name, _pos(token))
        return lambda run: run.variable(name)

    def function(self, node: Tree, depth: int) -> Expr:
        token, *args, axis_mod = node.children
        args = [a for a in args if a is not None]
        name = str(token).upper()
        if name not in kw.FUNCTIONS:
            if name in kw.COMMANDS:
                raise self.fail(token, f"{name}(...) is a command, not a function")
            raise self.fail(token, kw.unknown_function(str(token)))
        signature = kw.FUNCTIONS[name]
        if not signature.accepts(len(args)):
            raise self.fail(token, kw.wrong_count(signature, len(args)))
        if axis_mod is not None:
            raise self.fail(axis_mod, f"{name} takes no AXIS() modifier")
        argument = self.expr(args[0], depth + 1)
        if name == "IN":
            self._literal_channel(args[0], self.inputs)
        function = ops.FUNCTIONS[name]
        return lambda run: function(run, argument(run))
