"""The grammar of one G-code line (lark, LALR), as LinuxCNC's RS274/NGC reads the subset cosim runs.

A line is a sequence of words (a letter and a number: ``G1``, ``X-2.5``, ``F1200``) and comments
(``( ... )`` anywhere, ``;`` to the end of the line). Letters are case-insensitive; spaces and tabs
between words and between a letter and its number are ignored. Parameters (``#1``), expressions
(``[1+2]``), block delete (``/``) and O-words are outside the subset: they do not parse. Kept in
Python so it ships with the package.
"""

GRAMMAR = r"""
start: (word | COMMENT)*

word: LETTER NUMBER

LETTER: /[A-Za-z]/
NUMBER: /[+-]?([0-9]+(\.[0-9]*)?|\.[0-9]+)/
COMMENT: /\([^()\n]*\)/ | /;[^\n]*/

%ignore /[ \t\r\f]+/
"""
