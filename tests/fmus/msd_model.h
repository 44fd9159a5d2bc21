/*
 * The mass-spring-damper model shared by msd.c (FMI 2.0) and msd3.c (FMI 3.0), so the
 * two FMUs compute with the same arithmetic and, stepped alike, give the same bits:
 *
 *     m x'' = -k x - c x' + F
 *
 * F is held over each communication step; a step of length h integrates with classic
 * RK4 over n = ceil(h / 1e-4) equal substeps. A state is a copy of ModelData.
 */
#ifndef DSMCOSIM_MSD_MODEL_H
#define DSMCOSIM_MSD_MODEL_H

#include <math.h>

typedef struct {
    double m, k, c, x0, v0; /* parameters [kg], [N/m], [N s/m], [m], [m/s] */
    double F;               /* input [N] */
    double x, v;            /* state [m], [m/s] */
    double time;            /* [s] */
} ModelData;

/* Largest internal RK4 step [s]. */
#define MAX_SUBSTEP 1e-4

static void model_defaults(ModelData *d) {
    d->m = 1.0;
    d->k = 4.0;
    d->c = 0.4;
    d->x0 = 1.0;
    d->v0 = 0.0;
    d->F = 0.0;
    d->x = d->x0;
    d->v = d->v0;
    d->time = 0.0;
}

static double acceleration(const ModelData *d, double x, double v) {
    return (d->F - d->k * x - d->c * v) / d->m;
}

/* Integrates over h [s] with the held input; returns 0, or -1 (the state left as it
 * was) when the result is not finite. */
static int msd_integrate(ModelData *d, double h) {
    /* The small margin keeps h = 1 ms at 10 substeps despite 1e-3 / 1e-4 rounding up. */
    long n = (long)ceil(h / MAX_SUBSTEP - 1e-9);
    double dt, x = d->x, v = d->v;
    if (n < 1) n = 1;
    dt = h / (double)n;
    for (long i = 0; i < n; i++) {
        double k1x = v, k1v = acceleration(d, x, v);
        double k2x = v + 0.5 * dt * k1v, k2v = acceleration(d, x + 0.5 * dt * k1x, k2x);
        double k3x = v + 0.5 * dt * k2v, k3v = acceleration(d, x + 0.5 * dt * k2x, k3x);
        double k4x = v + dt * k3v, k4v = acceleration(d, x + dt * k3x, k4x);
        x += dt / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
        v += dt / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
    }
    if (!isfinite(x) || !isfinite(v) || !isfinite(acceleration(d, x, v))) return -1;
    d->x = x;
    d->v = v;
    return 0;
}

#endif
