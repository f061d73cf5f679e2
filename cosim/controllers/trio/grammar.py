"""The grammar of the Trio BASIC subset (lark, LALR).

Keywords are case-insensitive; an apostrophe starts a comment, also after code; statements are
separated by new lines or colons. Kept in Python so it ships with the package.
"""

GRAMMAR = r"""
start: _sep* (_stmt _sep+)*

_sep: _NL | ":"

_stmt: assign | index_assign | call | bare | wait_idle | wait_until
     | repeat | while_loop | for_loop | if_block | if_line

assign: NAME [axis_mod] _EQ expr
index_assign: NAME "(" _args ")" _EQ expr
call: NAME "(" _args ")" [axis_mod]
bare: NAME [axis_mod]
wait_idle: _WAIT _IDLE [axis_mod]
wait_until: _WAIT _UNTIL expr
repeat: _REPEAT _sep+ body _UNTIL expr
while_loop: _WHILE expr _sep+ body _WEND
for_loop: _FOR NAME _EQ expr _TO expr [_STEP expr] _sep+ body _NEXT [NAME]
if_block: _IF expr _THEN _sep+ body [_ELSE _sep+ body] _ENDIF
if_line: _IF expr _THEN (assign | index_assign | call | bare | wait_idle | wait_until)
body: (_stmt _sep+)*
axis_mod: _AXIS "(" expr ")"
_args: expr ("," expr)*

?expr: or_expr
?or_expr: or_expr _OR and_expr -> or_op
        | and_expr
?and_expr: and_expr _AND not_expr -> and_op
         | not_expr
?not_expr: _NOT not_expr -> not_op
         | comparison
?comparison: sum CMP sum -> compare
           | sum _EQ sum -> equal
           | sum
?sum: sum ADD term -> arith
    | term
?term: term MUL factor -> arith
     | factor
?factor: "-" factor -> neg
       | "+" factor
       | atom
?atom: NUMBER -> number
     | HEXNUM -> hexnumber
     | NAME [axis_mod] -> ref
     | _IDLE [axis_mod] -> idle_ref
     | NAME "(" _args ")" [axis_mod] -> func
     | "(" expr ")"

_WAIT: "WAIT"i
_IDLE: "IDLE"i
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
_ENDIF: "ENDIF"i
_AXIS: "AXIS"i
_AND: "AND"i
_OR: "OR"i
_NOT: "NOT"i

CMP: "<=" | ">=" | "<>" | "<" | ">"
_EQ: "="
ADD: "+" | "-"
MUL: "*" | "/"
NAME: /[a-z_][a-z0-9_]*/i
NUMBER: /([0-9]+(\.[0-9]*)?|\.[0-9]+)(e[-+]?[0-9]+)?/i
HEXNUM: /\$[0-9a-f]+/i
_NL: /\r?\n/
COMMENT: /'[^\n]*/

%ignore COMMENT
%ignore /[ \t\f]+/
"""
