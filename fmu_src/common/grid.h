/* The internal step grid of one doStep: the points t0 + k*h (k = 1, 2, ...), the last one capped
 * at the step's end. Each point derives from its counter k, never from a running sum, so the
 * internal steps do not depend on how the importer cuts the communication steps into doSteps.
 * Header only; shared by the plants that list "grid.h" under `shared` in their model.toml.
 *
 *     Grid grid;
 *     double t = t0, t_next;
 *     grid_start(&grid, t0, h, t_end);
 *     while (grid_next(&grid, t, &t_next)) {
 *         ... advance from t towards t_next; t = t_next (or an earlier instant: the next call
 *         ... gives the same t_next again)
 *     }
 */
#ifndef COSIM_GRID_H
#define COSIM_GRID_H

typedef struct {
    double t0;    /* [s] start of the doStep */
    double h;     /* [s] internal step */
    double t_end; /* [s] end of the doStep */
    long k;       /* index of the next grid point */
} Grid;

static inline void grid_start(Grid *g, double t0, double h, double t_end) {
    g->t0 = t0;
    g->h = h;
    g->t_end = t_end;
    g->k = 1;
}

/* The first grid point after t [s] (t_end if that comes first) in *t_next; 0 once t >= t_end. */
static inline int grid_next(Grid *g, double t, double *t_next) {
    while (t < g->t_end) {
        const double t_grid = g->t0 + (double)g->k * g->h;
        *t_next = t_grid < g->t_end ? t_grid : g->t_end;
        if (*t_next > t) {
            return 1;
        }
        g->k++;
    }
    return 0;
}

#endif
