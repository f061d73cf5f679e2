/* The bracketing root finder of the plant models: switching instants, encoder and mark edges,
 * switch crossings are all located by it. */
#include "roots.h"

static int crossed(double value, int strict) { return strict ? value > 0.0 : value >= 0.0; }

double root_after(ScalarFn g, const void *ctx, double a, double ga, double b, double gb, int strict, double tol) {
    int side = 0, slow = 0, i;
    if (crossed(ga, strict)) {
        return a; /* not a bracket (rounding at a turning point): the nearer end is the best answer */
    }
    if (!crossed(gb, strict)) {
        return b;
    }
    for (i = 0; i < 200 && b - a > tol; i++) {
        const double width = b - a;
        double t = (slow >= 2 || ga == gb) ? 0.5 * (a + b) : a + (b - a) * (ga / (ga - gb));
        double gt;
        if (!(t > a && t < b)) {
            t = 0.5 * (a + b);
        }
        gt = g(ctx, t);
        if (crossed(gt, strict)) {
            b = t;
            gb = gt;
            if (side == 1) {
                ga *= 0.5; /* Illinois: the same end moved twice */
            }
            side = 1;
        } else {
            a = t;
            ga = gt;
            if (side == -1) {
                gb *= 0.5;
            }
            side = -1;
        }
        slow = (b - a > 0.5 * width) ? slow + 1 : 0;
    }
    return b;
}

double passing(const void *p, double t) {
    const Passing *q = (const Passing *)p;
    return q->dir * (q->f(q->ctx, t) - q->level);
}

double root_sign_change(ScalarFn f, const void *ctx, double a, double fa, double b, double fb, double tol) {
    Passing z;
    z.f = f;
    z.ctx = ctx;
    z.level = 0.0;
    z.dir = fb > 0.0 ? 1.0 : (fb < 0.0 ? -1.0 : 0.0);
    return root_after(passing, &z, a, z.dir * fa, b, z.dir * fb, 1, tol);
}
