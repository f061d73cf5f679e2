"""The browser's copy of the pulse rule (the page's waveform script draws pulses with it when few are visible).

:data:`PULSES_JS` defines ``cosimPulses(seg, start, end, cap)``: the pulses of the segments ``seg``
(``{t0, duration, count, dir, width}``, arrays of exact integers in ticks, in order of ``t0``) inside
the window ``[start, end]`` (high at some instant of it: a pulse that rose before ``start`` and is
still high counts), placed by the rule of :mod:`cosim.pulses` (pulse ``k`` of a segment at
``t0 + floor(k * duration / count)``, ``width`` ticks high), or ``null`` when there are more than ``cap``. Integer
division is corrected after the float division, so the instants are exact while the products stay
below 2**53 (a segment's ``duration * count``). The browser test runs it against
:func:`cosim.pulses.materialize_pulses`.
"""

from __future__ import annotations

PULSES_JS = """
function cosimPulses(seg, start, end, cap) {
  const fdiv = (a, b) => {  // floor(a / b) of integers, exact while a < 2**53
    let q = Math.floor(a / b);
    if (q * b > a) { q -= 1; } else if ((q + 1) * b <= a) { q += 1; }
    return q;
  };
  const lo = Math.ceil(start), hi = Math.floor(end);
  const t = [], dir = [], w = [];
  for (let i = 0; i < seg.t0.length; i++) {
    const t0 = seg.t0[i], d = seg.duration[i], c = seg.count[i], wi = seg.width ? seg.width[i] : 1;
    if (t0 > hi) { break; }
    if (c <= 0 || t0 + d + wi <= lo) { continue; }
    // a pulse is in view while high: from the first whose fall (rise + width) is after lo
    const from = Math.min(Math.max(lo - wi + 1 - t0, 0), d), to = Math.min(Math.max(hi - t0 + 1, 0), d);
    const kmin = -fdiv(-from * c, d);          // first k with floor(k d / c) >= lo - width + 1 - t0
    const kmax = Math.min(c - 1, fdiv(to * c - 1, d));  // last k with floor(k d / c) <= hi - t0
    if (kmax < kmin) { continue; }
    if (t.length + kmax - kmin + 1 > cap) { return null; }
    for (let k = kmin; k <= kmax; k++) {
      t.push(t0 + fdiv(k * d, c)); dir.push(seg.dir[i]); w.push(wi);
    }
  }
  return {t: t, dir: dir, width: w};
}
"""
