/* The bracketing root finder of the plant models (roots.c). Shared by the plants that list
 * "roots.c" and "roots.h" under `shared` in their model.toml (and by encoder.c); the build copies
 * both into each FMU's sources/. */
#ifndef COSIM_ROOTS_H
#define COSIM_ROOTS_H

/* A scalar function of the time since a segment's origin [s]. */
typedef double (*ScalarFn)(const void *ctx, double t);

/* The crossing of g in [a, b], where g(a) = ga has not crossed and g(b) = gb has (crossed: g > 0
 * if strict, else g >= 0): the Illinois variant of regula falsi, with bisection when the bracket
 * shrinks slowly, until the bracket is at most tol wide (at most 200 evaluations of g). Returns the
 * bracket's upper end, a time at most tol after the crossing at which g has crossed. */
double root_after(ScalarFn g, const void *ctx, double a, double ga, double b, double gb, int strict, double tol);

/* f measured from a level in one direction, for root_after: passing(p, t) = dir * (f(t) - level)
 * has crossed 0 once f has passed the level going up (dir = +1) or down (dir = -1). */
typedef struct {
    ScalarFn f;
    const void *ctx;
    double level;
    double dir; /* +1 or -1 */
} Passing;

double passing(const void *p, double t);

/* The instant just after f changes sign in [a, b], where fa = f(a) and fb = f(b) have opposite
 * signs: root_after on f signed towards the sign of fb (crossed: strictly past 0). */
double root_sign_change(ScalarFn f, const void *ctx, double a, double fa, double b, double fb, double tol);

#endif
