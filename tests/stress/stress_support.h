/* The invariants the stress and thread tests check after every step, on a
 * "scene": a grid together with what the test knows about it (geometry, cell
 * kinds, open sides, whether a source acts).
 *
 *  - every height is finite;
 *  - the mass ledger closes: |total - (sourced + external - outflow)| is at
 *    most 1e-12 of the largest figure or gross mass (scene_ledger_residual);
 *  - without a source, no new extremum: a step's highest sand cell is no
 *    higher, and its lowest no lower, than the highest and lowest of the sand
 *    cells, the held levels of open cells and the levels beyond open sides
 *    (0 unless set) before it;
 *  - wall and open cells keep their heights;
 *  - no sand cell below the bed, when there is one;
 *  - when the step reports the surface at rest and nothing drives it (no
 *    source, every held level the same), no face is steeper than
 *    tan(theta) * (1 + tol) along an axis (sand-sand and sand-open faces, and
 *    an edge cell against the level beyond an open side);
 *  - on every second scene, which records its face fluxes: each sand cell's
 *    faces bring its change of height times its area less what its source
 *    added (with a bed: erosion takes at most what it asked), walls' faces
 *    carry nothing, each side's faces what its account took, and the sides
 *    and the open cells make up the outflow, to the round-off of the step's
 *    sub-steps.
 *
 * Each check records its worst figure (stress_worst) so that the tests can
 * print them. */
#ifndef DPSM_STRESS_SUPPORT_H
#define DPSM_STRESS_SUPPORT_H

#include <stddef.h>
#include <stdint.h>

#include <dpsm/dpsm.h>

enum { GEOM_1D = 1, GEOM_2D = 2, GEOM_AXI = 3 };

typedef struct {
    char name[160];
    dpsm_grid *g;
    int geom; /* GEOM_1D, GEOM_2D or GEOM_AXI */
    int scheme;
    int64_t nx, ny, n;
    double dx, dy, theta, tol;
    uint8_t *kinds; /* n values, all DPSM_CELL_SAND unless set */
    int open[4];    /* sides */
    int source;     /* a nonzero source acts on some sand cell */
    double *h;      /* heights after the last check */
    double *held;   /* heights of wall and open cells at the last host change */
    double mass_scale; /* the largest gross mass sum |h| * area at a host change */
    /* The physics of real scenes, NULL or 0 when not set. */
    double *bed;       /* no sand cell below it, ever */
    double *tan_field; /* tan of each cell's angle of repose */
    double tan_static; /* hysteresis */
    double *q;         /* the source as set; NULL: none */
    double *levels[4]; /* beyond each side, as set; NULL: 0 */
    int record;        /* face fluxes recorded and checked (every second scene) */
} scene_t;

/* Fails the test, naming the scene s (any struct with a name and a grid g)
 * and the library's message, when a call does not succeed (REQUIRE:
 * test_support.h). */
#define SCENE_OK(s, call)                                                                                      \
    do {                                                                                                       \
        const int st_ = (call);                                                                                \
        REQUIRE(st_ == DPSM_OK, "[%s] %s returned %s: %s", (s)->name, #call, dpsm_status_string(st_),        \
                dpsm_last_error((s)->g));                                                                      \
    } while (0)

/* The worst figures seen so far (over every scene of the process). */
typedef struct {
    double ledger;            /* relative ledger residual */
    double new_max_pairwise;  /* rise of the maximum over the allowed bound, relative to the height range */
    double new_min_pairwise;  /* fall of the minimum under the allowed bound, relative */
    double new_max_isotropic; /* the same for the isotropic scheme (2D) */
    double new_min_isotropic;
    double rest_slope; /* face slope at rest over tan(theta) * (1 + tol), minus 1 */
    double fluxes;     /* a sand cell's change against its faces and source, relative to its figures */
    long nonfinite;    /* heights found NaN or infinite */
    long checks;       /* states checked */
    long rest_checks;  /* states at rest checked */
    char ledger_where[160], max_where[160], min_where[160], iso_where[160], rest_where[160], fluxes_where[160];
} stress_worst_t;
extern stress_worst_t stress_worst;
void stress_worst_reset(stress_worst_t *w);
/* Folds w into stress_worst (tests keep their own, then merge). */
void stress_worst_merge(const stress_worst_t *w);
void stress_worst_print(const char *title, const stress_worst_t *w);

/* How much of the full workload to run: 1 normally, smaller under sanitizers
 * (DPSM_STRESS_SCALE in the environment, else the build's default). */
double stress_scale(void);
/* n scaled, at least lo. */
int64_t scaled(int64_t n, int64_t lo);

/* Deterministic random numbers (splitmix64). */
uint64_t rng_next(uint64_t *state);
double rng_uniform(uint64_t *state); /* [0, 1) */

/* Creates the grid (geom GEOM_1D/2D/AXI; ny, dy ignored off 2D) with default
 * parameters; every side a wall, every cell sand, no source. */
void scene_create(scene_t *s, const char *name, int geom, int64_t nx, int64_t ny, double dx, double dy);
void scene_destroy(scene_t *s);
void scene_set_scheme(scene_t *s, int scheme);
void scene_set_angle(scene_t *s, double theta);
void scene_set_tolerance(scene_t *s, double tol);
void scene_set_side(scene_t *s, int side, int open);
void scene_set_all_sides(scene_t *s, int open);
void scene_set_kinds(scene_t *s, const uint8_t *kinds);
void scene_set_heights(scene_t *s, const double *h);
void scene_set_source(scene_t *s, const double *q); /* NULL: none */
/* The physics setters; the rest check then uses each face's own law: the
 * mean tan of its cells' angles, the static angle between cells at rest, and
 * no bound where the upper cell holds no more sand above its bed than the
 * film dpsm leaves in place. */
void scene_set_bed(scene_t *s, const double *zb);
void scene_set_angle_field(scene_t *s, const double *theta);
void scene_set_static_angle(scene_t *s, double theta);
void scene_set_flux_exponent(scene_t *s, double p);
/* The levels beyond `side`, one per face (ny for the x sides, nx for the y
 * sides, one on 1D and axisymmetric grids); NULL: back to 0. */
void scene_set_side_levels(scene_t *s, int side, const double *levels);

/* Steps dt (must succeed) and checks every invariant against w. Returns 1 if
 * the step reported the surface at rest. */
int scene_step(scene_t *s, double dt, stress_worst_t *w);
/* Steps until the surface reports rest, at most max_calls calls of dt; fails
 * the test if it does not get there. */
void scene_run_to_rest(scene_t *s, double dt, int max_calls, stress_worst_t *w);
/* Whether the scene may flow forever: a source acts, or held levels differ
 * (open cells, and the levels beyond open sides). */
int scene_driven(const scene_t *s);
/* Checks every invariant of the current state (no step: max principle not
 * applied). */
void scene_check(scene_t *s, stress_worst_t *w);

/* dpsm_step(g, dt) must fail with DPSM_ERR_WORK_LIMIT, with a message that
 * says what to do, and change nothing dpsm shows of the grid of `ncells`
 * cells (heights, the ledger, the step information, the stable sub-step), bit
 * for bit; `name` names the scene in the failure. Any grid or mesh. */
void expect_work_limit_on(dpsm_grid *g, int64_t ncells, const char *name, double dt);
/* The same for any refusal: `status`, a message naming dpsm_step, dt and `needle`, nothing changed. */
void expect_step_refused_on(dpsm_grid *g, int64_t ncells, const char *name, double dt, int status,
                            const char *needle);

/* The relative ledger residual of g: relative to the largest of the four
 * figures, the gross mass sum |h| * area over sand cells now, and the largest
 * gross mass over all cells at a host change (what host changes booked). */
double scene_ledger_residual(const scene_t *s);

#endif
