/* Reference loop for benchmarks/c_reference.py: classical RK4 for one oscillator with a
 * Lankarani-Nikravesh Hertz stop, driven by a base motion tabulated on a uniform grid.
 *
 *   m x'' + b x' + k x + f(delta) = b y' + k y,   delta = x - y - gap (m),
 *   f = K delta^1.5 (1 + 3 (1 - e^2) / 4 * delta' / v_imp) for delta > 0, else 0,
 *
 * v_imp the approach speed delta' at the latest onset. y, y' between grid nodes: cubic
 * Hermite through (y, y') and through (y', y'') (the scheme of nlbeam.Sampled). Step dt
 * outside contact, dt_c inside. When a step changes the sign of delta, the crossing is
 * located on the step's cubic Hermite dense output (x, v at both ends) by Illinois false
 * position, and the step is redone from its start with the shortened length, so that it
 * ends on the crossing; the regime then switches. Nothing is stored: the loop returns the
 * end state and its counters.
 *
 * Usage: rk4_contact TABLE t_end dt dt_c K e gap x0 v0 v_imp0 repeats
 * TABLE: raw float64 [n, t0, h, y[n], y'[n], y''[n]]. Prints one line:
 * n_steps n_redone n_events x_end v_end best_cpu_seconds
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

static const double M_ = 37.75e-3, B_ = 0.16, K_ = 736.3;

typedef struct {
    double t0, h, inv_h;
    long n;
    const double *y, *yd, *ydd;
} grid_t;

typedef struct {
    double K, e, gap, v_imp;
    int contact;
} stop_t;

/* y and y' at time t (Hermite cubic on the grid cell holding t) */
static inline void base(const grid_t *g, double t, double *y, double *yd)
{
    double s = (t - g->t0) * g->inv_h;
    long j = (long)s;
    if (j < 0) j = 0;
    if (j > g->n - 2) j = g->n - 2;
    double u = s - (double)j, u2 = u * u, u3 = u2 * u;
    double a0 = 2.0 * u3 - 3.0 * u2 + 1.0, a1 = -2.0 * u3 + 3.0 * u2;
    double b0 = (u3 - 2.0 * u2 + u) * g->h, b1 = (u3 - u2) * g->h;
    *y = a0 * g->y[j] + b0 * g->yd[j] + a1 * g->y[j + 1] + b1 * g->yd[j + 1];
    *yd = a0 * g->yd[j] + b0 * g->ydd[j] + a1 * g->yd[j + 1] + b1 * g->ydd[j + 1];
}

static inline double accel(const grid_t *g, const stop_t *c, double t, double x, double v)
{
    double y, yd;
    base(g, t, &y, &yd);
    double f = 0.0;
    if (c->contact) {
        double d = x - y - c->gap;
        if (d > 0.0) {
            f = c->K * d * sqrt(d) * (1.0 + 0.75 * (1.0 - c->e * c->e) * (v - yd) / c->v_imp);
            if (f < 0.0) f = 0.0;
        }
    }
    return (B_ * (yd - v) + K_ * (y - x) - f) / M_;
}

static inline void rk4(const grid_t *g, const stop_t *c, double t, double x, double v,
                       double h, double *x1, double *v1)
{
    double k1x = v, k1v = accel(g, c, t, x, v);
    double k2x = v + 0.5 * h * k1v, k2v = accel(g, c, t + 0.5 * h, x + 0.5 * h * k1x, k2x);
    double k3x = v + 0.5 * h * k2v, k3v = accel(g, c, t + 0.5 * h, x + 0.5 * h * k2x, k3x);
    double k4x = v + h * k3v, k4v = accel(g, c, t + h, x + h * k3x, k4x);
    *x1 = x + h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
    *v1 = v + h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
}

static inline double gap_fn(const grid_t *g, const stop_t *c, double t, double x)
{
    double y, yd;
    base(g, t, &y, &yd);
    return x - y - c->gap;
}

/* delta on the step's dense output at fraction th (cubic Hermite in x) */
static double dense_delta(const grid_t *g, const stop_t *c, double t, double h, double x0,
                          double v0, double x1, double v1, double th)
{
    double t2 = th * th, t3 = t2 * th;
    double x = (2.0 * t3 - 3.0 * t2 + 1.0) * x0 + (t3 - 2.0 * t2 + th) * h * v0
               + (-2.0 * t3 + 3.0 * t2) * x1 + (t3 - t2) * h * v1;
    return gap_fn(g, c, t + th * h, x);
}

/* fraction of the step at which delta crosses zero (Illinois false position) */
static double locate(const grid_t *g, const stop_t *c, double t, double h, double x0, double v0,
                     double x1, double v1, double d0, double d1)
{
    double a = 0.0, b = 1.0, fa = d0, fb = d1;
    int side = 0;
    for (int it = 0; it < 60 && b - a > 1e-15; it++) {
        double m = (a * fb - b * fa) / (fb - fa);
        double fm = dense_delta(g, c, t, h, x0, v0, x1, v1, m);
        if ((fm > 0.0) == (fb > 0.0)) {
            b = m; fb = fm;
            if (side == -1) fa *= 0.5;
            side = -1;
        } else {
            a = m; fa = fm;
            if (side == 1) fb *= 0.5;
            side = 1;
        }
        if (fm == 0.0) return m;
    }
    return b;  /* the end on the new side of the boundary */
}

static void run(const grid_t *g, stop_t c, double t_end, double dt, double dt_c, double x,
                double v, long *n_steps, long *n_redone, long *n_events, double *xe, double *ve)
{
    double t = g->t0;
    long ns = 0, nr = 0, ne = 0;
    while (t < t_end) {
        double h = c.contact ? dt_c : dt;
        if (t + h > t_end) h = t_end - t;
        double x1, v1;
        rk4(g, &c, t, x, v, h, &x1, &v1);
        double d0 = gap_fn(g, &c, t, x), d1 = gap_fn(g, &c, t + h, x1);
        int crossed = c.contact ? (d1 <= 0.0) : (d1 > 0.0);
        if (crossed) {
            double th = locate(g, &c, t, h, x, v, x1, v1, d0, d1);
            h *= th;
            nr++;
            rk4(g, &c, t, x, v, h, &x1, &v1);
            ne++;
            if (!c.contact) {
                double y, yd;
                base(g, t + h, &y, &yd);
                c.v_imp = v1 - yd > 1e-12 ? v1 - yd : 1e-12;
            }
            c.contact = !c.contact;
        }
        t += h;
        x = x1;
        v = v1;
        ns++;
    }
    *n_steps = ns; *n_redone = nr; *n_events = ne; *xe = x; *ve = v;
}

int main(int argc, char **argv)
{
    if (argc != 12) {
        fprintf(stderr, "usage: %s TABLE t_end dt dt_c K e gap x0 v0 v_imp0 repeats\n", argv[0]);
        return 2;
    }
    FILE *fp = fopen(argv[1], "rb");
    if (!fp) { perror(argv[1]); return 2; }
    double head[3];
    if (fread(head, sizeof(double), 3, fp) != 3) { fprintf(stderr, "bad table\n"); return 2; }
    long n = (long)head[0];
    double *buf = malloc(3 * n * sizeof(double));
    if (!buf || fread(buf, sizeof(double), 3 * n, fp) != (size_t)(3 * n)) {
        fprintf(stderr, "bad table body\n");
        return 2;
    }
    fclose(fp);
    grid_t g = {head[1], head[2], 1.0 / head[2], n, buf, buf + n, buf + 2 * n};
    double t_end = atof(argv[2]), dt = atof(argv[3]), dt_c = atof(argv[4]);
    stop_t c = {atof(argv[5]), atof(argv[6]), atof(argv[7]), atof(argv[10]), 0};
    double x0 = atof(argv[8]), v0 = atof(argv[9]);
    int reps = atoi(argv[11]);
    c.contact = gap_fn(&g, &c, g.t0, x0) > 0.0;
    long ns = 0, nr = 0, ne = 0;
    double xe = 0.0, ve = 0.0, best = 1e300;
    for (int r = 0; r < reps; r++) {
        clock_t t0 = clock();
        run(&g, c, t_end, dt, dt_c, x0, v0, &ns, &nr, &ne, &xe, &ve);
        double s = (double)(clock() - t0) / CLOCKS_PER_SEC;
        if (s < best) best = s;
    }
    printf("%ld %ld %ld %.17g %.17g %.9g\n", ns, nr, ne, xe, ve, best);
    free(buf);
    return 0;
}
