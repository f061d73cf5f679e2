"""The grammar of the Trio BASIC subset (lark, LALR).

Keywords are case-insensitive; an apostrophe or ``REM`` starts a comment, also after code;
statements are separated by new lines or colons; a label is a name and a colon alone on its
line. The text reaching the parser has ``\\n`` line ends only (:func:`normalise_lines` maps every
line end Python knows, so line numbers match what an editor shows). Operator lists are flat
(``a + b - c`` is one node with its operators), so a long sum is not a deep tree. Kept in Python
so it ships with the package.
"""

from __future__ import annotations

GRAMMAR = r"""
start: _sep* (_stmt _sep+)*

_sep: _NL | ":"

_stmt: _simple | repeat | while_loop | for_loop | if_block | if_line | label

_simple: assign | index_assign | call | bare | wait_idle | wait_loaded | wait_until
       | goto | gosub | return_stmt | print_stmt | run_stmt

label: LABEL
assign: NAME [axis_mod] _EQ expr
index_assign: NAME "(" _args ")" _EQ expr
call: NAME "(" [_args] ")" [axis_mod]
bare: NAME [axis_mod]
wait_idle: _WAIT _IDLE [axis_mod]
wait_loaded: _WAIT _LOADED [axis_mod]
wait_until: _WAIT _UNTIL expr
goto: _GOTO NAME
gosub: _GOSUB NAME
return_stmt: _RETURN
print_stmt: _PRINT [print_item (print_sep print_item)* print_sep?]
print_item: expr | STRING
print_sep: _COMMA -> comma_sep
         | ";" -> semicolon_sep
run_stmt: _RUN STRING [_COMMA expr]
repeat: _REPEAT _sep+ body _UNTIL expr
while_loop: _WHILE expr _sep+ body _WEND
for_loop: _FOR NAME _EQ expr _TO expr [_STEP expr] _sep+ body _NEXT [NAME]
if_block: _IF expr _THEN _sep+ body elseif* [_ELSE _sep+ body] _ENDIF
elseif: _ELSEIF expr _THEN _sep+ body
if_line: _IF expr _THEN _simple [_ELSE _simple]
body: (_stmt _sep+)*
axis_mod: _AXIS "(" expr ")"
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
?term: factor (MUL factor)*
?factor: "-" factor -> neg
       | "+" factor
       | atom
?atom: NUMBER -> number
     | HEXNUM -> hexnumber
     | NAME [axis_mod] -> ref
     | _IDLE [axis_mod] -> idle_ref
     | _LOADED [axis_mod] -> loaded_ref
     | NAME "(" [_args] ")" [axis_mod] -> func
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
_GOTO: "GOTO"i
_GOSUB: "GOSUB"i
_RETURN: "RETURN"i
_PRINT: "PRINT"i
_RUN: "RUN"i
_NOT: "NOT"i
LOGIC_AND: "AND"i
LOGIC_OR: "OR"i | "XOR"i
MUL: "*" | "/" | "MOD"i
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


def normalise_lines(text: str) -> str:
    """``text`` with every line end Python's ``str.splitlines`` knows (CR, CRLF, VT, FF, NEL, ...) as ``\\n``.

    The parser, the error messages and an editor then count the same lines.

    Examples
    --------
    >>> normalise_lines("BASE(3)\\rATYPE=35\\r\\nx=1\\x85y=2")
    'BASE(3)\\nATYPE=35\\nx=1\\ny=2\\n'
    """
    return "".join(line + "\n" for line in text.splitlines())
