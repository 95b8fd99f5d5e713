/* What the study of larger steps (relax_study.c) shares with the study of
 * time-accurate super-time-stepping (sts_study.c). */
#ifndef DPSM_BENCH_RELAX_STUDY_H
#define DPSM_BENCH_RELAX_STUDY_H

#include <stdint.h>

/* The cone: h = max(0, 40 - 1.5 r), r from the centre cell, on n x n cells (dx unused). */
void fill_cone(double *h, int64_t n, double dx);
/* The cone's exact deposit at distance r: the cone of slope tan(theta) with its volume. */
double exact_cone(double r, double theta);
/* The largest of h[0 .. cells) and 0. */
double top_of(const double *h, int64_t cells);

/* The coefficients of a second-order Runge-Kutta-Chebyshev step of s stages
 * (Sommeijer, Shampine and Verwer 1997; damping 2/13), s <= 63. */
typedef struct {
    int s;
    double w0, w1, beta; /* beta: the step's stable length in units of 1 / lambda_max */
    double T[64], b[64];
} rkc_coefficients;

void rkc_setup(rkc_coefficients *k, int s);

#endif
