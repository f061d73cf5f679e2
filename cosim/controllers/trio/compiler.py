"""Check a Trio BASIC syntax tree and compile it into a flat list of operations.

Every check that does not need the machine is made here, before anything runs, and names the
program, the line, the column and the construct: an unknown keyword (with close matches), a wrong
number of arguments (with the allowed count and the usage), a label used but not defined or
defined twice, ``NEXT`` naming another loop, a one-line ``IF`` followed on its line by another
statement, a number literal beyond what a variable holds, nesting deeper than :data:`MAX_NESTING`,
``DIM ... AS`` an unknown type, a name read but never assigned (a misspelt keyword), a misspelt
parameter assigned and never read (``UNIT = 16``).

Variables are created on first assignment, as on the controller; ``DIM`` declares typed variables
and arrays; ``CONSTANT`` and ``GLOBAL`` names are known to every program of a machine
(:class:`~.expressions.Declarations`); ``INCLUDE "file"`` compiles another file's statements in
place (its errors name that file).

The program becomes a list of operations ``op(run, pc) -> next pc``; loops, ``IF``, ``GOTO``,
``GOSUB`` and ``ON ... GOTO`` are jumps, so running a program needs no recursion.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from lark import Token, Tree

from cosim.controllers.trio import keywords as kw
from cosim.controllers.trio import operations as ops
from cosim.controllers.trio.commands import HANDLERS, not_modelled, setting
from cosim.controllers.trio.expressions import MAX_NESTING, Declarations, ExpressionCompiler, _mods, pos
from cosim.controllers.trio.printing import compile_input, compile_print
from cosim.controllers.trio.runtime import BasicError, Compiled, store_variable
from cosim.controllers.trio.syntax import parse
from cosim.controllers.trio.values import DEFAULT_STRING_LENGTH, Datum, integer_part, literal, typed
from cosim.errors import ConfigurationError

if TYPE_CHECKING:
    from cosim.controllers.trio.runtime import BasicRun

Op = ops.Op
Expr = ops.Expr
#: Arguments PWM_CONTROL takes after the mode, by mode (TN20-81).
PWM_CONTROL_ARGS = {0: 0, 1: 0, 2: 4, 3: 4, 4: 0, 5: 0, 6: 0}
#: Resolves ``INCLUDE "name"`` to (file name, text); None when the program has no file to look beside.
Includer = Callable[[str], tuple[str, str]]


def declarations_of(tree: Tree, into: Declarations, name: str) -> None:
    """Collect the ``CONSTANT`` and ``GLOBAL`` names of ``tree`` (before any program is compiled)."""
    collector = Compiler(name, declarations=into)
    for node in tree.iter_subtrees_topdown():
        if node.data in ("constant_stmt", "global_stmt"):
            collector.declare(node)


class Compiler(ExpressionCompiler):
    """Checks and compiles one program (see the module docstring)."""

    def __init__(self, name: str, *, declarations: Declarations | None = None, include: Includer | None = None
                 ) -> None:
        self.name = name
        self.file = name
        self.declarations = declarations if declarations is not None else Declarations()
        self.include = include
        self.ops: list[Op] = []
        self.sources: list[tuple[str, int]] = []
        self.labels: dict[str, int] = {}
        self.jumps: list[tuple[int, list[str], Tree | Token, str]] = []  # (op index, labels, node, kind)
        self.assigned: dict[str, tuple[int, int]] = {}
        self.read: dict[str, tuple[int, int]] = {}
        self.arrays: dict[str, int] = {}
        self.typed: set[str] = set()
        self.inputs: set[int] = set()
        self.outputs: set[int] = set()
        self.included: list[str] = []
        self._on_selectors: dict[int, Expr] = {}

    def compile(self, tree: Tree) -> Compiled:
        for node in tree.iter_subtrees_topdown():  # names declared anywhere are known everywhere
            if node.data in ("constant_stmt", "global_stmt"):
                self.declare(node)
            elif node.data == "dim_decl":
                self._dim_shape(node)
        self.block(tree, 0)
        for index, targets, node, kind in self.jumps:
            missing = [t for t in targets if t not in self.labels]
            if missing:
                known = ", ".join(sorted(self.labels)) or "none"
                raise self.fail(node, f"label {missing[0]} is not defined (labels: {known})")
            pcs = [self.labels[t] for t in targets]
            if kind == "goto":
                self.ops[index] = ops.jump(pcs[0])
            elif kind == "gosub":
                self.ops[index] = ops.gosub(pcs[0])
            elif kind in ("error_goto", "error_gosub"):
                target, sub = pcs[0], kind == "error_gosub"
                self.ops[index] = ops.action(lambda run, target=target, sub=sub: setattr(  # type: ignore[misc]
                    run, "error_handler", (target, sub)))
            else:
                self.ops[index] = self._patched_on_jump(index, pcs, kind == "on_gosub")
        for var, (line, column) in self.read.items():
            if var not in self.assigned and var not in self.typed:
                raise ConfigurationError(f"{self.name} line {line}, column {column}: {kw.unknown_name(var)} (not a "
                                         "keyword, nor a variable the program assigns)")
        for var, (line, column) in self.assigned.items():
            near = kw.misspelt_parameter(var)
            if var not in self.read and near is not None:
                raise ConfigurationError(f"{self.name} line {line}, column {column}: {kw.unknown_name(var)} "
                                         f"(assigned but never read: a misspelt {near}?)")
        return Compiled(tuple(self.ops), tuple(self.sources), frozenset(self.inputs), frozenset(self.outputs),
                        dict(self.labels))

    def emit(self, node: Tree | Token, op: Op) -> int:
        self.ops.append(op)
        self.sources.append((self.file, pos(node)[0]))
        return len(self.ops) - 1

    # -- statements ---------------------------------------------------------------------------
    def block(self, tree: Tree, depth: int) -> None:
        if depth > MAX_NESTING:
            raise self.fail(tree, f"blocks nested deeper than {MAX_NESTING} levels")
        nodes = [c for c in tree.children if isinstance(c, Tree)]
        for k, node in enumerate(nodes):
            if node.data == "if_line" and k + 1 < len(nodes) and pos(nodes[k + 1])[0] == node.meta.end_line:
                raise self.fail(nodes[k + 1], "a one-line IF governs one statement; this one would run whatever "
                                              "the condition (write IF ... THEN, the statements, ENDIF)")
            self.statement(node, depth)

    def statement(self, node: Tree, depth: int) -> None:
        getattr(self, f"s_{node.data}")(node, depth)

    def s_label(self, node: Tree, depth: int) -> None:
        token = node.children[0]
        name = str(token).rstrip(": \t").upper()
        if name in kw.KEYWORDS:
            raise self.fail(token, f"{name} is a keyword, not a label (remove the colon)")
        if name in self.labels:
            raise self.fail(token, f"label {name} is defined twice")
        self.labels[name] = len(self.ops)

    def s_assign(self, node: Tree, depth: int) -> None:
        token, index_node, mods, value_node = node.children
        assert isinstance(token, Token)
        name = str(token).upper()
        axis_mod, proc_mod = _mods(mods)
        value = self.expr(value_node, 0)
        if index_node is not None:
            self._assign_indexed(node, token, name, index_node, axis_mod or proc_mod, value)
            return
        if name in self.declarations.constants or name in kw.CONSTANTS:
            raise self.fail(token, f"{name} is a constant; it cannot be assigned")
        if name in self.declarations.globals:
            slot = self.declarations.globals[name]
            self.emit(node, ops.action(lambda run: run.controller.set_vr(slot, value(run))))
            return
        if name in kw.PROCESS_PARAMS:
            self._assign_process_param(node, token, name, axis_mod, proc_mod, value)
            return
        if name in kw.WRITABLE:
            if proc_mod is not None:
                raise self.fail(proc_mod, f"{name} is not a process parameter; it takes no PROC()")
            if axis_mod is not None and (name == "WDOG" or name in kw.SYSTEM_WRITABLE):
                raise self.fail(token, f"{name} is not an axis parameter; write {name} = value without AXIS()")
            axis = self.axis(axis_mod)

            def set_parameter(run: BasicRun, pc: int) -> int:
                process = run.process
                process.origin = run.where
                process.set(name, value(run), axis=axis(run))
                return pc + 1

            self.emit(node, set_parameter)
            return
        if name in kw.READABLE:
            hint = " (use DEFPOS)" if name in ("DPOS", "MPOS") else ""
            raise self.fail(token, f"{name} is read-only{hint}")
        if name in kw.KEYWORDS:
            raise self.fail(token, kw.misplaced(name, "assignment") or f"cannot assign to {name}")
        if axis_mod is not None or proc_mod is not None:
            raise self.fail(token, kw.unknown_name(name) + " (AXIS() and PROC() only modify parameters)")
        if name in self.arrays:
            raise self.fail(token, f"{name} is an array; assign an element with {name}(index) = value")
        self.assigned.setdefault(name, pos(token))
        store = store_variable

        def assign(run: BasicRun, pc: int) -> int:
            store(run, name, value(run))
            return pc + 1

        self.emit(node, assign)

    def _assign_process_param(self, node: Tree, token: Token, name: str, axis_mod: Tree | None,
                              proc_mod: Tree | None, value: Expr) -> None:
        if axis_mod is not None:
            raise self.fail(token, f"{name} is not an axis parameter; write {name} = value without AXIS()")
        if name not in kw.PROCESS_WRITABLE:
            raise self.fail(token, f"{name} is read-only")
        proc = self.proc(proc_mod)
        self.emit(node, ops.action(lambda run: run.program_control.set_process_param(run, name, value(run),
                                                                                      proc(run))))

    def _assign_indexed(self, node: Tree, token: Token, name: str, index_node: Tree, mod: Tree | None,
                        value: Expr) -> None:
        args = [a for a in index_node.children if a is not None]
        if mod is not None:
            raise self.fail(mod, f"{name}(...) takes no AXIS() or PROC() modifier")
        if name == "VR":
            if len(args) != 1:
                raise self.fail(token, kw.wrong_count(kw.FUNCTIONS["VR"], len(args)))
            index = self.expr(args[0], 0)
            self.emit(node, ops.action(lambda run: run.controller.set_vr(index(run), value(run))))
            return
        if name == "TABLE":
            if len(args) != 1:
                raise self.fail(token, kw.wrong_count(kw.FUNCTIONS["TABLE"], len(args)))
            index = self.expr(args[0], 0)
            self.emit(node, ops.action(lambda run: run.process.table(index(run), value(run))))
            return
        if name not in self.arrays:
            raise self.fail(token, f"cannot assign to {token}(...); write VR(n) = value, TABLE(n, value), or DIM "
                                   f"{token}(size) first")
        element = self.index(name, [self.expr(a, 1) for a in args])
        dims = self.arrays[name]
        if len(args) != dims:
            raise self.fail(node, f"{name} has {dims} dimension{'s' if dims > 1 else ''}; {len(args)} given")

        def assign(run: BasicRun, pc: int) -> int:
            k = element(run)
            kind = run.types.get(name)
            datum = value(run)
            run.arrays[name][k] = datum if kind is None else typed(datum, kind[0], name, kind[1])
            return pc + 1

        self.emit(node, assign)

    def s_call(self, node: Tree, depth: int) -> None:
        token, *args, mods = node.children
        args = [a for a in args if a is not None]
        name = str(token).upper()
        if name not in kw.ALL_COMMANDS:
            if name in self.arrays:
                raise self.fail(token, f"{name}(...) is an array element; assign it with {name}(index) = value")
            raise self.fail(token, kw.misplaced(name, "command") or kw.unknown_command(str(token)))
        self.command(node, kw.ALL_COMMANDS[name], args, mods)

    def s_string_call(self, node: Tree, depth: int) -> None:
        token, text, *args = node.children
        name = str(token).upper()
        if name not in kw.ALL_COMMANDS:
            raise self.fail(token, kw.misplaced(name, "command") or kw.unknown_command(str(token)))
        string = Tree("string", [text], meta=node.meta)
        self.command(node, kw.ALL_COMMANDS[name], [string, *[a for a in args if a is not None]], None)

    def s_channel_call(self, node: Tree, depth: int) -> None:
        """``OPEN #5 AS "log" FOR OUTPUT``, ``CLOSE #5``: a command whose first argument is a channel."""
        token, channel, *rest = node.children
        *args, as_node, mode = rest
        name = str(token).upper()
        if name not in kw.ALL_COMMANDS:
            raise self.fail(token, kw.misplaced(name, "channel") or kw.unknown_command(str(token)))
        word = None if mode is None else "INPUT" if mode.data == "mode_input" else str(mode.children[0]).upper()
        words = [] if word is None else [Tree("string", [Token("STRING", f'"{word}"')], meta=node.meta)]
        extra = [a for a in (*args, as_node) if a is not None]
        self.command(node, kw.ALL_COMMANDS[name], [channel, *extra, *words], None)

    def s_bare(self, node: Tree, depth: int) -> None:
        token, mods = node.children
        name = str(token).upper()
        if name in kw.ALL_COMMANDS:
            signature = kw.ALL_COMMANDS[name]
            if signature.low:
                raise self.fail(token, f"{name} needs its arguments: {signature.usage}")
            self.command(node, signature, [], mods)
        elif name in self.declarations.globals:
            raise self.fail(token, f"{name} is a parameter; write {name} = value")
        else:
            raise self.fail(token, kw.misplaced(name, "command") or kw.unknown_command(str(token)))

    def command(self, node: Tree, signature: kw.Signature, args: list[Any], mods: Tree | None) -> None:
        name = signature.name
        axis_mod, proc_mod = _mods(mods)
        if not signature.accepts(len(args)):
            raise self.fail(node, kw.wrong_count(signature, len(args)))
        if axis_mod is not None and not signature.axis_modifier:
            raise self.fail(axis_mod, f"{name} takes no AXIS() modifier")
        if proc_mod is not None:
            raise self.fail(proc_mod, f"{name} takes no PROC() modifier")
        values = [self.expr(a, 0) for a in args]
        axis = self.axis(axis_mod)
        if name == "PWM_CONTROL" and isinstance(args[0], Tree) and args[0].data == "number":
            mode = literal(str(args[0].children[0]))
            if isinstance(mode, int) and mode in PWM_CONTROL_ARGS and len(args) - 1 != PWM_CONTROL_ARGS[mode]:
                wanted = PWM_CONTROL_ARGS[mode] + 1
                raise self.fail(node, f"number of PWM_CONTROL({mode}) arguments = {len(args)} is not allowed "
                                      f"(allowed: {wanted}, the mode and {wanted - 1} more)")
        if name == "OP" and len(args) == 2:
            self.literal_channel(args[0], self.outputs)
        handler = (HANDLERS[name] if name in HANDLERS else setting(name) if name in kw.SETTINGS
                   else not_modelled(name))

        def op(run: BasicRun, pc: int) -> int:
            run.process.origin = run.where
            run.pending = handler(run, [v(run) for v in values], axis(run))
            return pc + 1

        self.emit(node, op)

    def s_wait_idle(self, node: Tree, depth: int) -> None:
        axis = self._axis_only(node, "WAIT IDLE")
        self.emit(node, ops.wait(lambda run: run.process.wait_idle(axis=axis(run))))

    def s_wait_loaded(self, node: Tree, depth: int) -> None:
        axis = self._axis_only(node, "WAIT LOADED")
        self.emit(node, ops.wait(lambda run: run.process.wait_loaded(axis=axis(run))))

    def _axis_only(self, node: Tree, what: str) -> Callable[[BasicRun], Any]:
        axis_mod, proc_mod = _mods(node.children[0])
        if proc_mod is not None:
            raise self.fail(proc_mod, f"{what} takes AXIS(), not PROC()")
        return self.axis(axis_mod)

    def s_wait_until(self, node: Tree, depth: int) -> None:
        condition = self.expr(node.children[0], 0)
        truth = ops.truth
        memory_only = self.memory_only(node.children[0])

        def wait_until(run: BasicRun, pc: int) -> int:
            if truth(condition(run)):
                return pc + 1
            run.pending = run.next_servo_tick(memory_only=memory_only)
            return pc  # checked again at the next servo tick

        self.emit(node, wait_until)

    def s_goto(self, node: Tree, depth: int) -> None:
        self.jumps.append((self.emit(node, ops.jump(-1)), [str(node.children[0]).upper()], node.children[0], "goto"))

    def s_gosub(self, node: Tree, depth: int) -> None:
        self.jumps.append((self.emit(node, ops.jump(-1)), [str(node.children[0]).upper()], node.children[0],
                           "gosub"))

    def s_on_error(self, node: Tree, depth: int) -> None:
        kind, token = node.children
        self.jumps.append((self.emit(node, ops.jump(-1)), [str(token).upper()], token,
                           "error_gosub" if kind.data == "kind_gosub" else "error_goto"))

    def s_on_jump(self, node: Tree, depth: int) -> None:
        selector, kind, *tokens = node.children
        self._on_selectors[len(self.ops)] = self.expr(selector, 0)
        self.jumps.append((self.emit(node, ops.jump(-1)), [str(t).upper() for t in tokens], tokens[0],
                           "on_gosub" if kind.data == "kind_gosub" else "on_goto"))

    def _patched_on_jump(self, index: int, pcs: list[int], sub: bool) -> Op:
        return ops.on_jump(self._on_selectors.pop(index), pcs, sub=sub)

    def s_return_stmt(self, node: Tree, depth: int) -> None:
        self.emit(node, lambda run, pc: run.return_from_gosub())

    def s_print_stmt(self, node: Tree, depth: int) -> None:
        compile_print(self, node)

    def s_input_stmt(self, node: Tree, depth: int) -> None:
        compile_input(self, node, "INPUT")

    def s_get_stmt(self, node: Tree, depth: int) -> None:
        compile_input(self, node, "GET")

    def s_linput_stmt(self, node: Tree, depth: int) -> None:
        compile_input(self, node, "LINPUT")

    def s_dim_stmt(self, node: Tree, depth: int) -> None:
        for decl in node.children:
            self._dim(decl)

    def _dim_shape(self, decl: Tree) -> None:
        token, index_node, _type_token, _length = decl.children
        if index_node is not None:
            self.arrays[str(token).upper()] = len([a for a in index_node.children if a is not None])
        self.typed.add(str(token).upper())

    def _dim(self, decl: Tree) -> None:
        token, index_node, type_token, length_node = decl.children
        name = str(token).upper()
        if name in kw.KEYWORDS or name in self.declarations.constants or name in self.declarations.globals:
            raise self.fail(token, f"DIM {name}: {name} is a keyword or a declared name, not a new variable")
        kind = "FLOAT" if type_token is None else str(type_token).upper()
        if kind not in kw.TYPES:
            raise self.fail(type_token, f"DIM ... AS {type_token} is not a type (allowed: {', '.join(kw.TYPES)})")
        if length_node is not None and kind != "STRING":
            raise self.fail(type_token, f"DIM ... AS {kind}(...): only STRING takes a length")
        length = (self.constant_value(length_node.children[0], "the length of a STRING") if length_node is not None
                  else DEFAULT_STRING_LENGTH)
        sizes_exprs = [self.expr(a, 0) for a in index_node.children if a is not None] if index_node is not None else []
        self.assigned.setdefault(name, pos(token))
        string_length = integer_part(length) if not isinstance(length, str) else DEFAULT_STRING_LENGTH

        def dim(run: BasicRun, pc: int) -> int:
            initial: Datum = "" if kind == "STRING" else 0
            run.types[name] = (kind, string_length)
            if sizes_exprs:
                sizes = []
                for size_expr in sizes_exprs:
                    size = size_expr(run)
                    n = integer_part(size) if not isinstance(size, str) else -1
                    if not 1 <= n <= 1_000_000:
                        raise BasicError(f"DIM {name} size = {n} is not allowed (allowed: 1..1000000)", 1)
                    sizes.append(n)
                total = 1
                for n in sizes:
                    total *= n
                if total > 1_000_000:
                    raise BasicError(f"DIM {name}: {total} elements are not allowed (allowed: at most 1000000)", 1)
                run.array_sizes[name] = tuple(sizes)
                run.arrays[name] = [initial] * total
            else:
                run.variables[name] = initial
            return pc + 1

        self.emit(decl, dim)

    def declare(self, node: Tree) -> None:
        """Record a CONSTANT or GLOBAL declaration (its value must be known before the program runs)."""
        token, value_node = node.children
        assert isinstance(token, Token)
        name = (str(token)[1:-1] if token.type == "STRING" else str(token)).upper()
        what = "CONSTANT" if node.data == "constant_stmt" else "GLOBAL"
        if not name or not name.replace("_", "a").isalnum() or not (name[0].isalpha() or name[0] == "_"):
            raise self.fail(token, f"{what} {token}: the name must be a letter or _ followed by letters, digits, _")
        if name in kw.KEYWORDS:
            raise self.fail(token, f"{what} \"{name}\": {name} is a keyword")
        value = self.constant_value(value_node, f"the value of {what} {name}")
        if what == "CONSTANT":
            known = self.declarations.constants.get(name)
            if known is not None and known != value:
                raise self.fail(token, f"CONSTANT {name} is declared twice with different values")
            self.declarations.constants[name] = value
        else:
            index = integer_part(value) if not isinstance(value, str) else -1
            if index < 0:
                raise self.fail(value_node, f"GLOBAL {name}: the VR index must be a number >= 0")
            self.declarations.globals[name] = index

    def s_constant_stmt(self, node: Tree, depth: int) -> None:
        self.declare(node)  # known from the start of the program (and of every program of the machine)

    def s_global_stmt(self, node: Tree, depth: int) -> None:
        self.declare(node)

    def s_include_stmt(self, node: Tree, depth: int) -> None:
        token = node.children[0]
        target = str(token)[1:-1]
        if self.include is None:
            raise self.fail(token, f"INCLUDE \"{target}\": the program has no folder to find it in")
        try:
            file, text = self.include(target)
        except ConfigurationError as exc:
            raise self.fail(token, f"INCLUDE \"{target}\": {exc}") from None
        if file in self.included or file == self.name or len(self.included) > 32:
            raise self.fail(token, f"INCLUDE \"{target}\" includes itself (through {', '.join(self.included)})")
        tree = parse(text, file)
        outer = (self.name, self.file)
        self.included.append(file)
        self.name = self.file = file
        try:
            for sub in tree.iter_subtrees_topdown():
                if sub.data in ("constant_stmt", "global_stmt"):
                    self.declare(sub)
                elif sub.data == "dim_decl":
                    self._dim_shape(sub)
            self.block(tree, depth + 1)
        finally:
            self.name, self.file = outer
            self.included.pop()

    def s_repeat(self, node: Tree, depth: int) -> None:
        body, condition_node = node.children
        start = len(self.ops)
        self.block(body, depth + 1)
        condition = self.expr(condition_node, 0)
        truth = ops.truth
        self.emit(condition_node, lambda run, pc: pc + 1 if truth(condition(run)) else start)

    def s_while_loop(self, node: Tree, depth: int) -> None:
        condition_node, body = node.children
        condition = self.expr(condition_node, 0)
        top = self.emit(node, ops.jump(-1))
        self.block(body, depth + 1)
        self.emit(node, ops.jump(top))
        self.ops[top] = ops.jump_unless(condition, len(self.ops))

    def s_for_loop(self, node: Tree, depth: int) -> None:
        token, start_node, stop_node, step_node, body, next_token = node.children
        var = str(token).upper()
        if next_token is not None and str(next_token).upper() != var:
            raise self.fail(next_token, f"NEXT {next_token} closes FOR {token}")
        if var in kw.KEYWORDS or var in self.declarations.constants:
            raise self.fail(token, f"cannot use {var} as a loop variable")
        self.assigned.setdefault(var, pos(token))
        self.read.setdefault(var, pos(token))
        start, stop = self.expr(start_node, 0), self.expr(stop_node, 0)
        step = ops.constant(1) if step_node is None else self.expr(step_node, 0)
        load, store = self._loop_variable(var)
        init = self.emit(node, ops.jump(-1))
        self.block(body, depth + 1)
        next_op = self.emit(next_token if next_token is not None else body if not body.meta.empty else node,
                            ops.for_next(var, init, init + 1, load, store))
        self.ops[init] = ops.for_init(var, start, stop, step, next_op + 1, store)

    def _loop_variable(self, var: str) -> tuple[Callable[[BasicRun, str], Datum],
                                                Callable[[BasicRun, str, Datum], None]]:
        if var in self.declarations.globals:
            slot = self.declarations.globals[var]
            return (lambda run, name: run.controller.vr(slot),
                    lambda run, name, value: run.controller.set_vr(slot, value))
        return (lambda run, name: run.variable(name)), store_variable

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
            self.ops[test] = ops.jump_unless(condition, len(self.ops))
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
