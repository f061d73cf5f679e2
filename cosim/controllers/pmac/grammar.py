"""The grammar of Turbo PMAC text (lark, LALR): one line at a time, online commands or program statements.

A PMAC file is read line by line (after the download preprocessor, :mod:`.preprocess`): a line
outside ``OPEN ... CLOSE`` is parsed from ``online_line`` (commands the controller executes at
once), a line inside a buffer from ``program_line`` (statements of a motion, PLC or kinematic
program). Blocks that span lines (``IF ... ENDIF``, ``WHILE ... ENDWHILE``, ``OPEN ... CLOSE``,
conditions continued by ``AND`` / ``OR`` lines) are matched by :mod:`.program`, not here, so the
parse never recurses over lines. Keywords are case-insensitive; ``;`` starts a comment.

The forms are those of the Turbo PMAC Software Reference (on-line commands and program commands).
Commands the model does not act on (``LIST``, ``SAVE``, ``DEFINE GATHER``, ``MS`` MACRO commands,
``CC1``, ``BLOCKSTART``, ...) are one rule, ``other``: a keyword and the rest of its statement, kept
as written (see :mod:`.syntax`); the runtime lists them as "set, not modelled".

The parser is built once, the first time a line is parsed (:func:`parser`), never at import.
"""

from __future__ import annotations

from functools import cache
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from lark import Lark

#: Keywords of commands that are accepted and kept but do not act in the model (followed by any arguments).
OTHER_ONLINE = (
    "LIST", "SAVE", "SIZE", "VERSION", "TYPE", "DATE", "TODAY", "TIME", "CID", "CPU", "VID", "SID", "EAVERSION",
    "IDNUMBER", "IDC", "STN", "PASSWORD", "DEFINE", "DELETE", "GATHER", "ENDGATHER", "ENDG", "MFLUSH", "MOVETIME",
    "UPDATE", "LEARN", "LOCK", "UNLOCK", "SETPHASE", "PC", "PE", "PR", "MACROASCII", "MACROAUX", "MACROAUXREAD",
    "MACROAUXWRITE", "MACROMST", "MACROMSTASCII", "MACROMSTREAD", "MACROMSTWRITE", "MACROSLV", "MACROSLVREAD",
    "MACROSLVWRITE", "MACROSTASCII", "MSCLRERR", "MSDATE", "MSFIND", "MSR", "MSREAD", "MSSAV", "MSVER", "MSW",
    "MSWRITE", "MS", "RH", "RHX", "RHY", "RHL", "RHD", "RX", "RY", "RL", "RD", "WX", "WY", "WL", "WD", "UNDEFINE",
    "BREQ", "BSTART", "BSTOP",
    "END", "TCOMP", "BLCOMP", "COMP",
)
OTHER_PROGRAM = (
    "BLOCKSTART", "BLOCKSTOP", "BSTART", "BSTOP", "CCR", "CC0", "CC1", "CC2", "CC3", "ADIS", "IDIS", "AROT", "IROT",
    "TR", "TINIT", "TSELECT", "TXYZ", "TYZX", "TZXY", "LOCK", "UNLOCK", "READ", "PRELUDE", "PRELUDE0", "PRELUDE1",
    "SETPHASE", "MACROAUXREAD", "MACROAUXWRITE", "MACROSLVREAD", "MACROSLVWRITE", "MACROMSTREAD", "MACROMSTWRITE",
    "SPLINE2", "PSET", "TSEL", "STOP", "WAIT", "GATHER", "ENDGATHER", "ENDG", "NX", "NY", "NZ", "TX", "TY", "TZ",
)


def _words(words: tuple[str, ...]) -> str:
    """A regex alternation of keywords, longest first, each ending at a word boundary.

    A number may follow a keyword at once (``MS0,MI910``, ``MSR1``, ``LOCK4``, ``CCR2.5``).
    """
    return "(?:" + "|".join(sorted(set(words), key=lambda w: (-len(w), w))) + ")(?![A-Z_])"


GRAMMAR = r"""
online_line: _online*
_online: cs_select | motor_select | motor_def | motor_query | open_buffer | close_buffer | clear_buffer | begin
       | cs_command | p0_assign
       | percent | percent_query | assign | range_assign | mdef | mdef_query | query | range_query | plc_control
       | motor_command | axis_set | control_char | frax | pmatch | home_cmd | other_online | undefine

cs_select: _CS_AMP data
motor_select: "#" data
motor_def: "#" INT "->" axis_def
motor_query: "#" INT "->"
axis_def: INVKIN -> axis_inverse
        | SCALE -> axis_null
        | [SIGN] axis_term (SIGN axis_term)* [SIGN SCALE] -> axis_linear
axis_term: [SCALE] AXIS
open_buffer: _OPEN BUFFER [INT] [CLEAR_KW] -> open_buffer
           | _OPEN ROTARY_KW [CLEAR_KW] -> open_rotary
close_buffer: CLOSE_KW [ALL_KW]
clear_buffer: CLEAR_KW [ALL_KW]
p0_assign: [SIGN] (INT | NUMBER | HEX)
begin: _B data
cs_command: CS_LETTER
percent: PERCENT_SET data
percent_query: PERCENT_Q
range_assign: var_range "=" (expr | DEFAULT)
assign: var "=" (expr | DEFAULT)
range_query: var_range
query: var
var_range: (IVAR | PVAR | QVAR | MVAR) _DOTS INT -> var_span
         | (IVAR | PVAR | QVAR | MVAR) "," INT ["," INT] -> var_step
mdef: (MVAR | mrange) "->" _mtarget
mdef_query: MVAR "->"
mrange: MVAR _DOTS INT
_mtarget: mword | mself | mwide | mthumb
mword: MSPACE address ["," INT ["," INT ["," MFORMAT]]]
mwide: MWIDE address
mthumb: MTHUMB INT ("," INT)*
mself: "*"
?address: INT | HEX
plc_control: PLC_VERB PLC_KW plc_list
plc_list: plc_item ("," plc_item)*
plc_item: INT [_DOTS INT]
motor_command: JOG [data] -> jog
             | MOTOR_Q -> motor_report
             | OPEN_LOOP data -> open_loop
axis_set: AXIS "=" data
control_char: CTRL
frax: FRAX_KW ["(" AXIS ("," AXIS)* ")"]
pmatch: PMATCH_KW
home_cmd: HOME_KW [plc_list]
undefine: UNDEFINE_KW [ALL_KW]
other_online: OTHER_ON [REST]
            | OTHER_SYM [REST]
            | PORT_SELECT

program_line: [label] [cont] _stmt*
label: _N INT
_stmt: assign | mod_assign | move | mode | modal_axes | param | dwell | delay | if_head | while_head | else_head
     | endif | endwhile | goto | gosub | call | return | plc_control | cmd | send | display | address_cmd | frax
     | home_cmd | normal | code_call | other_program | pmatch | pvt | close_buffer | clear_buffer

mod_assign: MVAR MOD_OP expr
move: move_word+ center_word*
move_word: AXIS data [":" data] -> move_word
         | AXIS data _TRIGGER data -> trigger_word
center_word: CENTER data -> center
           | IVAR -> center_ivar
           | RADIUS data -> radius
mode: MODE
modal_axes: ABSINC "(" AXIS ("," AXIS)* ")"
pvt: PVT_KW data
param: PARAM data
dwell: _DWELL data
delay: _DELAY data
if_head: _IF condition
while_head: _WHILE condition
cont: LOGIC condition
else_head: _ELSE
endif: _ENDIF
endwhile: _ENDWHILE
goto: _GOTO data
gosub: _GOSUB data
call: _CALL data [call_args]
call_args: (_arg_letter data | IVAR)+
_arg_letter: ARG_LETTER | AXIS | CENTER | RADIUS
return: _RETURN
cmd: _CMD (STRING | CTRL)
send: SEND_KW (STRING | CTRL)
display: _DISPLAY [INT] STRING -> display_text
       | _DISPLAY INT "," INT "." INT "," var -> display_var
address_cmd: _ADDRESS (address_item)+
address_item: _CS_AMP data -> address_cs
            | "#" data -> address_motor
normal: _NORMAL center_word+
code_call: CODE_LETTER data
         | MVAR -> mcode
other_program: OTHER_PROG [REST]

var: IVAR | PVAR | QVAR | MVAR | VARIND "(" expr ")"
data: [SIGN] value
?value: NUMBER -> number
      | INT -> number
      | HEX -> hexnumber
      | ADDRESS_OF -> address_of
      | var
      | "(" expr ")"

?condition: cond_or
?cond_or: cond_and (_OR cond_and)*
?cond_and: cond_atom (_AND cond_atom)*
?cond_atom: expr CMP expr -> compare
          | expr "=" expr -> equal
          | "(" cond_or ")"

?expr: sum
?sum: product ((ADDOP | BITXOR) product)*
?product: unary ((MULOP | BITAND) unary)*
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
BUFFER.2: /(PROGRAM|PROG|PLCC|PLC|FORWARD|FWD|INVERSE|INV)(?![A-Z])/i
ROTARY_KW.2: /(BINARY\s+)?(ROTARY|ROT)(?![A-Z])/i
CLEAR_KW.2: /CLEAR(?![A-Z])/i
CLOSE_KW.2: /CLOSE(?![A-Z])/i
ALL_KW.2: /ALL(\s+PLCS)?(?![A-Z])/i
UNDEFINE_KW.3: /UNDEFINE(?![A-Z])/i
_B.2: /B(?=\s*[0-9($@-])/i
CS_LETTER.2: /[RSHAQK](?![A-Z0-9]|\s*[-+=(.0-9$])/i | /[\/\\](?!\s*[-+(.0-9$@A-Za-z])/
PERCENT_Q: /%(?!\s*[0-9.($@+-])/
PERCENT_SET: /%(?=\s*[0-9.($@+-])/
_DOTS: ".."
DEFAULT: "*"
INVKIN: /I(?![A-Z0-9])/i
JOG: /J(?:[+-](?!\s*[0-9.(])|\/|!|=\s*\*|[:^]\s*\*|=|:|\^)/i
MOTOR_Q: /[PVF](?![A-Z0-9(]|\s*[-+(.0-9$])/i
OPEN_LOOP: /O(?=\s*[-0-9(])/i
PLC_VERB.2: /(ENABLE|ENA|DISABLE|DIS|PAUSE|RESUME)(?![A-Z])/i
PLC_KW: /PLCC?(?![A-Z])/i
FRAX_KW.2: /(NOFRAX2|NOFRAX|FRAX2|FRAX)(?![A-Z0-9])/i
PMATCH_KW.2: /PMATCH(?![A-Z])/i
HOME_KW.2: /(HOMEZ|HOME|HMZ|HM)(?![A-Z])/i
OTHER_ON.1: /@OTHER_ONLINE@/i
OTHER_PROG.1: /@OTHER_PROGRAM@/i
REST: /[^;\r\n]+/
PORT_SELECT.2: /##\s*[0-9]*|@\s*[0-9A-F]?(?![0-9A-Z])/i
OTHER_SYM: /(\$\$\$\*\*\*|\$\$\$|\$\$\*|\$\$|\$\*|\$|\?\?\?|\?\?|\?)(?![0-9A-F])/i
_N: /[NO](?=\s*[0-9])/i
_IF: /IF(?![A-Z])/i
_WHILE: /WHILE(?![A-Z])/i
_ELSE: /ELSE(?![A-Z])/i
_ENDIF: /(ENDIF|ENDI)(?![A-Z])/i
_ENDWHILE: /(ENDWHILE|ENDW)(?![A-Z])/i
_DWELL: /(DWELL|DWE)(?![A-Z])/i
_DELAY: /(DELAY|DEL)(?![A-Z])/i
_GOTO: /GOTO(?![A-Z])/i
_GOSUB: /GOSUB(?![A-Z])/i
_CALL: /CALL(?![A-Z])/i
_RETURN: /(RETURN|RET)(?![A-Z])/i
_CMD: /(COMMAND|CMD)[SPRA]?(?![A-Z])/i
SEND_KW: /SEND[12SPCRA]?(?![A-Z0-9])/i
_DISPLAY: /(DISPLAY|DISP)(?![A-Z])/i
_ADDRESS: /(ADDRESS|ADR)(?![A-Z])/i
_NORMAL: /(NORMAL|NRM)(?![A-Z])/i
_AND: /AND(?![A-Z])/i
_OR: /OR(?![A-Z])/i
LOGIC: /(AND|OR)(?![A-Z])/i
MODE: /(LINEAR|LIN|RAPID|RPD|CIRCLE1|CIRCLE2|CIR1|CIR2|SPLINE1|SPL1|ABS|INC)(?![A-Z0-9])/i
ABSINC.2: /(ABS|INC)(?=\s*\()/i
PVT_KW: /PVT(?![A-Z])/i
PARAM: /(TA|TS|TM|F)(?![A-Z])/i
FUNC: /(ABS|INT|SIN|COS|TAN|ASIN|ACOS|ATAN2|ATAN|SQRT|LN|EXP|EXP2)(?=\s*\()/i
CODE_LETTER: /[GTD](?=\s*[0-9.(-])/i
ARG_LETTER.-1: /[A-Z](?![A-Z])/i
AXIS: /[XYZABCUVW](?![A-Z])/i
CENTER: /[IJK](?![A-Z])/i
RADIUS: /R(?![A-Z])/i
MSPACE: /(X|Y)\s*:/i
MWIDE: /(DP|D|L|F)\s*:/i
MTHUMB: /TW[SBDR]\s*:/i
MFORMAT: /[SU](?![A-Z])/i
MOD_OP: "==" | "&=" | "|=" | "^="
SIGN: "-" | "+"
IVAR: /I[0-9]+(?![0-9]|\.[0-9])/i
PVAR: /P[0-9]+/i
QVAR: /Q[0-9]+/i
MVAR: /M[0-9]+/i
VARIND: /[IPQM](?=\s*\()/i
CMP: "!=" | "<>" | "!>" | "!<" | "!~" | ">=" | "<=" | ">" | "<" | "~"
ADDOP: "+" | "-" | "|"
BITXOR.3: /\^(?!=)/
_TRIGGER: /\^/
MULOP: "*" | "/" | "%"
BITAND.3: /&(?!=)/
_CS_AMP: /&/
INT: /[0-9]+/
NUMBER: /[0-9]+\.[0-9]*|\.[0-9]+/
SCALE: /[0-9]+(\.[0-9]*)?|\.[0-9]+/
HEX: /\$[0-9A-F]+/i
ADDRESS_OF: /@I[0-9]+/i
STRING: /"[^"]*"/
CTRL: /\^[A-Z@\[\\\]^_]/i | /[\x01-\x08\x0b\x0e-\x1a]/
COMMENT: /;.*/

%ignore COMMENT
%ignore /[ \t]+/
""".replace("@OTHER_ONLINE@", _words(OTHER_ONLINE)).replace("@OTHER_PROGRAM@", _words(OTHER_PROGRAM))


@cache
def parser(context: str) -> Lark:
    """The LALR parser of ``online_line`` or ``program_line`` (built on first use, then kept).

    One parser per context, so that a letter is lexed by what its context allows (``K`` kills in
    an online line and is a circle-centre word in a program; ``J+`` jogs, ``J-10`` is a centre).
    Building one takes about a second; :func:`cosim.controllers.grammars.lark_parser` keeps the built
    tables in the per-user cache (keyed by the grammar's hash), so later processes load them instead.
    """
    from cosim.controllers.grammars import lark_parser

    return lark_parser(GRAMMAR, parser="lalr", start=f"{context}_line", propagate_positions=True,
                       maybe_placeholders=True)
