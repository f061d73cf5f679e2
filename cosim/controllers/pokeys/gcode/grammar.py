"""The grammar of one RS274/NGC line as LinuxCNC 2.9 reads it (lark, LALR), kept in Python so it ships.

LinuxCNC reads a line after taking out every space and tab outside comments and lowering the case
of every letter outside comments (``G1 X 1 . 5`` is ``g1x1.5``); :mod:`.syntax` does the same and
keeps a map back to the columns of the text as written. What is left is:

* an optional block delete ``/`` and line number ``N``, at the start;
* words: a letter (``@`` and ``^`` are the polar words) and a real value: a number, a parameter
  (``#12``, ``#<name>``, ``#[1+2]``, ``##1``), an expression in brackets, a function
  (``sin[30]``, ``atan[1]/[2]``, ``exists[#<x>]``) or a value with a sign (``x-#1``);
* parameter settings ``#12=value``, ``#<name>=value``;
* comments ``( ... )`` and ``; ...``;
* an O-word: ``o100 sub``, ``o<name> call [1] [2]``, ``o1 if [#1 gt 0]``, ...

Operators in expressions, highest precedence first: ``**``; ``*`` ``/`` ``mod``; ``+`` ``-``;
``eq ne gt ge lt le``; ``and or xor``; all left-associative. A sign binds tighter than ``**``
(``-2**2`` is 4).
"""

GRAMMAR = r"""
start: BLOCK_DELETE? line_number? _item*

line_number: "n" NUMBER
_item: word | setting | COMMENT | oword

word: LETTER value
setting: "#" index "=" value

oword: "o" label OKEY oarg*
label: NAME -> named_label
     | value -> numbered_label
oarg: "[" expr "]"

?value: NUMBER -> number
      | "-" value -> neg
      | "+" value
      | parameter
      | "[" expr "]"
      | FUNC "[" expr "]" -> func
      | "atan" "[" expr "]" "/" "[" expr "]" -> atan
      | "exists" "[" "#" NAME "]" -> exists

parameter: "#" index
index: NAME -> named
     | value -> numbered

?expr: expr LOGOP comparison -> binary
     | comparison
?comparison: comparison CMPOP sum -> binary
           | sum
?sum: sum addop product -> binary
    | product
?product: product mulop power -> binary
        | power
?power: power "**" value -> power
      | value

!addop: "+" | "-"
!mulop: "*" | "/" | "mod"

BLOCK_DELETE: "/"
LETTER: /[a-mp-z@^$]/
NUMBER: /[0-9]+\.?[0-9]*|\.[0-9]+/
NAME: /<[^<>]*>/
FUNC: "abs" | "acos" | "asin" | "cos" | "exp" | "fix" | "fup" | "round" | "ln" | "sin" | "sqrt" | "tan"
LOGOP: "and" | "or" | "xor"
CMPOP: "eq" | "ne" | "gt" | "ge" | "lt" | "le"
OKEY: "sub" | "endsub" | "call" | "do" | "while" | "endwhile" | "if" | "elseif" | "else" | "endif"
    | "repeat" | "endrepeat" | "break" | "continue" | "return"
COMMENT: /\([^()]*\)/ | /;.*/
"""
