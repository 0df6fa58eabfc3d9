/**
# granudep independent check: does a thin mu(I) layer stop on a slope below its static friction?

A uniform layer of thickness H (N cells) on a periodic bed at THETA, no-slip bed, launched as a plug
at U0. In the continuum, mu(I) >= mu_s > tan(theta) wherever the layer shears, so it must stop. A
cell-centred mu(I) viscosity sees the first cell's centre pressure, p_b - rho g cos(theta) Delta/2,
so the bed friction of an N-cell layer is short by a factor (N - 1/2)/N. With -DBEDSTRESS the bed
face's viscosity is taken at the bed's normal stress instead (granudep's wall.bed_stress: bed).

Usage: layer THETA_DEG H DELTA U0 T_END D_EFF MUS DMU I0 ETAMAX_SI RHO OUTPREFIX
Writes OUTPREFIX.stats: t [s], mean speed of the grains, speed of the first cell row, max speed (m/s).
*/
#include "grid/multigrid.h"
#ifdef BEDSTRESS
double bed_pn = 0.;
#include "granular_bed.h"
#else
#include "granular.h"
#endif
#define GSI 9.81
double TU, VU, theta, hl, u0si, tend_si, etamax_si, rho_bulk;
char prefix[512];
FILE * fstat;
face vector av[];

p[top] = dirichlet(0.);
pf[top] = dirichlet(0.);
u.n[top] = neumann(0.);
u.t[bottom] = dirichlet(0.);

int main (int argc, char * argv[])
{
  if (argc < 13) { fprintf (stderr, "usage: layer THETA_DEG H DELTA U0 T_END D_EFF MUS DMU I0 ETAMAX_SI RHO OUTPREFIX\n"); return 1; }
  theta = atof(argv[1])*pi/180.;
  hl = atof(argv[2]);
  double delta = atof(argv[3]);
  u0si = atof(argv[4]); tend_si = atof(argv[5]);
  D = atof(argv[6]); mus = atof(argv[7]); dmu = atof(argv[8]); I0 = atof(argv[9]);
  etamax_si = atof(argv[10]); rho_bulk = atof(argv[11]);
  strncpy (prefix, argv[12], 500);
  TU = sqrt(1./GSI); VU = sqrt(GSI);
#ifdef BEDSTRESS
  bed_pn = 0.5*cos(theta);
#endif
  etamax = etamax_si/(rho_bulk*sqrt(GSI));

  dimensions (nx = 4, ny = 2);
  size (64*delta);
  origin (0., 0.);
  periodic (right);
  init_grid (64);
  DT = 2e-3/TU;
  a = av;
  char name[600];
  sprintf (name, "%s.stats", prefix); fstat = fopen (name, "w");
  fprintf (fstat, "# t_s mean_speed base_speed max_speed  (dx = %g m, layer %g m)\n", L0/N, hl);
  run();
  fclose (fstat);
}

event init (t = 0) {
  fraction (f, hl - y);
  foreach() {
    p[] = f[]*cos(theta)*max(hl - y, 0.);
    u.x[] = y < hl ? 1.6666666666667*u0si/VU*(1. - pow(1. - y/hl, 1.5)) : 1.6666666666667*u0si/VU; // Bagnold shape, mean U0
  }
}

event acceleration (i++) {
  foreach_face(x) av.x[] += sin(theta);
  foreach_face(y) av.y[] -= cos(theta);
}

event output_stats (t += 0.01/sqrt(1./GSI)) {
  double vol = 0., mom = 0., bvol = 0., bmom = 0., vmax = 0.;
  foreach (serial) {
    double dv = f[]*sq(Delta), sp = u.x[]*VU;
    vol += dv; mom += dv*sp;
    if (y < Delta) { bvol += dv; bmom += dv*sp; }
    if (f[] > 0.5 && fabs(sp) > vmax) vmax = fabs(sp);
  }
  double tsi = t*TU;
  fprintf (fstat, "%.4f %.6g %.6g %.6g\n", tsi, mom/vol, bvol > 0 ? bmom/bvol : 0., vmax);
  fflush (fstat);
  if (tsi >= tend_si - 1e-9) return 1;
  return 0;
}
event end (t = 1e4) {}
