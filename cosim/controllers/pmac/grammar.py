"""The grammar of PMAC text (lark, LALR): one line at a time, online commands or program statements.

A PMAC file is read line by line: a line outside ``OPEN ... CLOSE`` is parsed from ``online_line``
(commands the controller executes at once), a line inside a buffer from ``program_line`` (statements
of a motion or PLC program). Blocks that span lines (``IF ... ENDIF``, ``WHILE ... ENDWHILE``,
``OPEN ... CLOSE``) are matched by :mod:`.program`, not here, so the parse never recurses over
lines. Keywords are case-insensitive; ``;`` starts a comment. Kept in Python so it ships with the
package.
"""

GRAMMAR = r"""
online_line: _online*
_online: cs_select | motor_def | motor_select | open_buffer | clear | close | begin | run | hold
       | percent | assign | mdef | query | plc_enable | plc_disable

cs_select: "&" INT
motor_select: "#" INT
motor_def: "#" INT "->" [SIGN] [SCALE] AXIS
_decimal: INT | NUMBER
open_buffer: _OPEN BUFFER INT
clear: _CLEAR
close: _CLOSE
begin: _B INT
run: _R
hold: _H
percent: "%" _decimal
mdef: MVAR "->" _mtarget
_mtarget: mword | mself
mword: MSPACE address ["," INT ["," INT ["," MFORMAT]]]
mself: "*"
?address: INT | HEX
query: var

program_line: [label] _stmt*
label: _N INT
_stmt: assign | mode | param | axis | dwell | delay | if_head | while_head | else_head | endif | endwhile
     | goto | gosub | call | return | plc_enable | plc_disable | cmd | clear | close
if_head: _IF condition
while_head: _WHILE condition
else_head: _ELSE
endif: _ENDIF
endwhile: _ENDWHILE
mode: MODE
param: PARAM expr
axis: AXIS expr
dwell: _DWELL expr
delay: _DELAY expr
goto: _GOTO INT
gosub: _GOSUB INT
call: _CALL INT
return: _RETURN
cmd: _CMD STRING
plc_enable: _ENABLE _PLC INT ("," INT)*
plc_disable: _DISABLE _PLC INT ("," INT)*

assign: var "=" expr
var: IVAR | PVAR | MVAR

?condition: cond_or
?cond_or: cond_and (_OR cond_and)*
?cond_and: cond_atom (_AND cond_atom)*
?cond_atom: expr CMP expr -> compare
          | expr "=" expr -> equal
          | "(" cond_or ")"

?expr: sum
?sum: product (ADDOP product)*
?product: unary (MULOP unary)*
?unary: "-" atom -> neg
      | "+" atom
      | atom
?atom: NUMBER -> number
     | INT -> number
     | HEX -> hexnumber
     | ADDRESS_OF -> address_of
     | var
     | FUNC "(" expr ")" -> func
     | "(" expr ")"

_OPEN: "OPEN"i
BUFFER: "PROGRAM"i | "PROG"i | "PLC"i
_CLEAR: "CLEAR"i
_CLOSE: "CLOSE"i
_B: /B/i
_R: "R"i
_H: "H"i
_N: "N"i | "O"i
_IF: "IF"i
_WHILE: "WHILE"i
_ELSE: "ELSE"i
_ENDIF: "ENDIF"i | "ENDI"i
_ENDWHILE: "ENDWHILE"i | "ENDW"i
_DWELL: "DWELL"i | "DWE"i
_DELAY: "DELAY"i | "DEL"i
_GOTO: "GOTO"i
_GOSUB: "GOSUB"i
_CALL: "CALL"i
_RETURN: "RETURN"i | "RET"i
_CMD: "CMD"i
_ENABLE: "ENABLE"i | "ENA"i
_DISABLE: "DISABLE"i | "DIS"i
_PLC: "PLC"i
_AND: "AND"i
_OR: "OR"i
MODE: "LINEAR"i | "RAPID"i | "ABS"i | "INC"i
PARAM: "TA"i | "TS"i | "TM"i | "F"i
FUNC: "ABS"i | "INT"i
AXIS: /[XYZABCUVW](?![A-Z])/i
MSPACE: /[XY]:/i
MFORMAT: /[SU](?![A-Z])/i
SIGN: "-" | "+"
IVAR: /I[0-9]+/i
PVAR: /P[0-9]+/i
MVAR: /M[0-9]+/i
CMP: "!=" | "<>" | "!>" | "!<" | ">=" | "<=" | ">" | "<"
ADDOP: "+" | "-" | "|" | "^"
MULOP: "*" | "/" | "%" | "&"
INT: /[0-9]+/
NUMBER: /[0-9]+\.[0-9]*|\.[0-9]+/
SCALE: /[0-9]+(\.[0-9]*)?|\.[0-9]+/
HEX: /\$[0-9A-F]+/i
ADDRESS_OF: /@I[0-9]+/i
STRING: /"[^"]*"/
COMMENT: /;.*/

%ignore COMMENT
%ignore /[ \t]+/
"""
