"""Text to syntax tree: the grammar of Trio BASIC (lark, LALR), built once on first use.

Keywords are case-insensitive; an apostrophe or ``REM`` starts a comment, also after code;
statements are separated by new lines or colons; a label is a name and a colon alone on its
line. The text reaching the parser has ``\\n`` line ends only (:func:`normalise_lines` maps every
line end Python knows, so line numbers match what an editor shows). Operator lists are flat
(``a + b - c`` is one node with its operators), so a long sum is not a deep tree.

The grammar is generic where the language is: any ``NAME``, ``NAME(args)``, ``NAME = value``,
each with ``AXIS(n)`` / ``PROC(n)`` modifiers, and ``NAME "text", args`` (``RUN "PROG", 3``,
``STOP "PROG"``) is a statement the parser accepts; what a name means (a command, a parameter, a
variable), how many arguments it takes and whether it is modelled is decided by the compiler
(:mod:`.compiler`), which names the construct in its messages. Only the statements with a syntax of
their own have rules: ``PRINT``/``INPUT``/``GET``/``LINPUT`` with ``#channel``, a command on a
channel (``OPEN #5 AS "log" FOR OUTPUT``, ``CLOSE #5``), ``DIM ... AS``, ``CONSTANT``, ``GLOBAL``,
``INCLUDE``, ``ON BASICERROR``, ``ON ... GOTO/GOSUB``, ``WAIT``, the loops and ``IF``. So a statement
the manual documents is never a syntax error.

The LALR parser is built on the first :func:`parser` call and kept (building it costs tens of
milliseconds: never at import time).
"""

from __future__ import annotations

from functools import cache

from lark import Lark

GRAMMAR = r"""
start: _sep* (_stmt _sep+)*

_sep: _NL | ":"

_stmt: _simple | repeat | while_loop | for_loop | if_block | if_line | label

_simple: assign | call | bare | string_call | channel_call | wait_idle | wait_loaded | wait_until | goto | gosub
       | return_stmt | print_stmt | input_stmt | get_stmt | linput_stmt | dim_stmt | constant_stmt
       | global_stmt | include_stmt | on_error | on_jump

label: LABEL
assign: NAME [index] mods _EQ expr
call: NAME "(" [_args] ")" mods
bare: NAME mods
string_call: NAME STRING (_COMMA expr)*
channel_call: NAME "#" atom (_COMMA expr)* [_AS expr] [_FOR open_mode]
open_mode: _INPUT -> mode_input
         | NAME -> mode_name
mods: (axis_mod | proc_mod)*
index: "(" _args ")"
wait_idle: _WAIT _IDLE mods
wait_loaded: _WAIT _LOADED mods
wait_until: _WAIT _UNTIL expr
goto: _GOTO NAME
gosub: _GOSUB NAME
return_stmt: _RETURN
print_stmt: (_PRINT | _QUERY) [channel] [print_item (print_sep print_item)* print_sep?]
channel: "#" atom _COMMA
print_item: expr [print_format]
print_format: "[" expr [_COMMA expr] "]"
print_sep: _COMMA -> comma_sep
         | ";" -> semicolon_sep
input_stmt: _INPUT [channel] [STRING (_COMMA | ";")] target (_COMMA target)*
get_stmt: _GET [channel] target
linput_stmt: _LINPUT [channel] target
target: NAME [index]
dim_stmt: _DIM dim_decl (_COMMA dim_decl)*
dim_decl: NAME [index] [_AS NAME [index]]
constant_stmt: _CONSTANT (STRING | NAME) (_COMMA | _EQ) expr
global_stmt: _GLOBAL (STRING | NAME) (_COMMA | _EQ) expr
include_stmt: _INCLUDE STRING
on_error: _ON _BASICERROR jump_kind NAME
on_jump: _ON expr jump_kind NAME (_COMMA NAME)*
jump_kind: _GOTO -> kind_goto
         | _GOSUB -> kind_gosub
repeat: _REPEAT _sep+ body _UNTIL expr
while_loop: _WHILE expr _sep+ body _WEND
for_loop: _FOR NAME _EQ expr _TO expr [_STEP expr] _sep+ body _NEXT [NAME]
if_block: _IF expr _THEN _sep+ body elseif* [_ELSE _sep+ body] _ENDIF
elseif: _ELSEIF expr _THEN _sep+ body
if_line: _IF expr _THEN _simple [_ELSE _simple]
body: (_stmt _sep+)*
axis_mod: _AXIS "(" expr ")"
proc_mod: _PROC "(" expr ")"
_args: expr (_COMMA expr)*

?expr: or_expr
?or_expr: and_expr (LOGIC_OR and_expr)*
?and_expr: not_expr (LOGIC_AND not_expr)*
?not_expr: _NOT not_expr -> not_op
         | comparison
?comparison: comparison CMP sum -> compare
           | comparison _EQ sum -> equal
           | sum
?sum: term (ADD term)*
?term: pow_expr (MUL pow_expr)*
?pow_expr: factor (POW factor)*
?factor: "-" factor -> neg
       | "+" factor
       | atom
?atom: NUMBER -> number
     | HEXNUM -> hexnumber
     | STRING -> string
     | NAME mods -> ref
     | _ON mods -> on_const
     | _IDLE mods -> idle_ref
     | _LOADED mods -> loaded_ref
     | NAME "(" [_args] ")" mods -> func
     | NAME "#" atom -> channel_func
     | "(" expr ")"

_WAIT: "WAIT"i
_IDLE: "IDLE"i
_LOADED: "LOADED"i
_UNTIL: "UNTIL"i
_REPEAT: "REPEAT"i
_WHILE: "WHILE"i
_WEND: "WEND"i
_FOR: "FOR"i
_TO: "TO"i
_STEP: "STEP"i
_NEXT: "NEXT"i
_IF: "IF"i
_THEN: "THEN"i
_ELSE: "ELSE"i
_ELSEIF: "ELSEIF"i
_ENDIF: "ENDIF"i
_AXIS: "AXIS"i
_PROC: "PROC"i
_GOTO: "GOTO"i
_GOSUB: "GOSUB"i
_RETURN: "RETURN"i
_PRINT: "PRINT"i
_QUERY: "?"
_INPUT: "INPUT"i
_GET: "GET"i
_LINPUT: "LINPUT"i
_DIM: "DIM"i
_AS: "AS"i
_CONSTANT: "CONSTANT"i
_GLOBAL: "GLOBAL"i
_INCLUDE: "INCLUDE"i
_ON: "ON"i
_BASICERROR: "BASICERROR"i
_NOT: "NOT"i
LOGIC_AND: "AND"i
LOGIC_OR: "OR"i | "XOR"i
MUL: "*" | "/" | "MOD"i
POW: "^"
ADD: "+" | "-"
CMP: "<=" | ">=" | "<>" | "<" | ">"
_EQ: "="
_COMMA: ","

LABEL.2: /[a-z_][a-z0-9_]*[ \t]*:(?=[ \t]*('[^\n]*)?\n)/i
NAME: /[a-z_][a-z0-9_]*/i
NUMBER: /([0-9]+(\.[0-9]*)?|\.[0-9]+)(e[-+]?[0-9]+)?/i
HEXNUM: /\$[0-9a-f]+/i
STRING: /"[^"\n]*"/
_NL: /\n/
COMMENT: /'[^\n]*/
REMARK: /REM(?![a-z0-9_])[^\n]*/i

%ignore COMMENT
%ignore REMARK
%ignore /[ \t]+/
"""

#: How the parser's terminals read in a syntax error message.
TERMINALS = {"_NL": "end of line", "NAME": "a name", "NUMBER": "a number", "HEXNUM": "a $hex number",
             "STRING": "a \"string\"", "LABEL": "a label", "LPAR": "(", "RPAR": ")", "COMMA": ",", "_COMMA": ",",
             "COLON": ":", "SEMICOLON": ";", "MINUS": "-", "PLUS": "+", "_EQ": "=", "CMP": "a comparison",
             "ADD": "+ or -", "MUL": "* / MOD", "POW": "^", "LOGIC_AND": "AND", "LOGIC_OR": "OR XOR",
             "LSQB": "[", "RSQB": "]", "__ANON_0": "#", "$END": "end of program"}


#: The options of the parser (the shape of its trees depends on them as on :data:`GRAMMAR`).
PARSER_OPTIONS = {"parser": "lalr", "propagate_positions": True, "maybe_placeholders": True}


@cache
def parser() -> Lark:
    """The LALR parser of :data:`GRAMMAR`, built on the first call and kept (and cached on disk by
    :func:`cosim.controllers.grammars.lark_parser`, so a new process loads it instead of building it)."""
    from cosim.controllers.grammars import lark_parser

    return lark_parser(GRAMMAR, **PARSER_OPTIONS)


def normalise_lines(text: str) -> str:
    """``text`` with every line end Python's ``str.splitlines`` knows (CR, CRLF, VT, FF, NEL, ...) as ``\\n``.

    The parser, the error messages and an editor then count the same lines.

    Examples
    --------
    >>> normalise_lines("BASE(3)\\rATYPE=35\\r\\nx=1\\x85y=2")
    'BASE(3)\\nATYPE=35\\nx=1\\ny=2\\n'
    """
    return "".join(line + "\n" for line in text.splitlines())
