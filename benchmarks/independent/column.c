/**
# granudep independent check: granular column collapse with Basilisk + granular.h

Our driver for P.-Y. Lagree's sandbox `granular.h` (mu(I) rheology of Jop, Forterre & Pouliquen,
two-phase VOF with a light passive fluid). It solves the problem granudep's 2D ISPH solver solves
with `wall.slip: no_slip`: slope-aligned frame (x down-slope, y bed-normal), gravity
(g sin theta, -g cos theta), column [0,L0]x[0,H0] against a back wall at x = 0, no-slip bed and
no-slip back wall, incompressible mu(I) with granudep's material (passed on the command line by
run_basilisk.sh, which reads them from granudep's config).

Units inside Basilisk: length in m, g = 1 (time unit T = sqrt(1 m / 9.81 m s-2)), density of the
granular phase (bulk density rho) = 1 (granular.h's convention). Hence:
 - I = d |gdot| / sqrt(p/rho_s) (granudep) becomes granular.h's I = D |gdot| / sqrt(p)
   with D = d sqrt(rho_s/rho) (m);
 - a viscosity cap eta_max [Pa s] becomes eta_max / (rho sqrt(g) 1 m^1.5).
Every output is converted back to SI (s, m, m/s).

Usage: column THETA_DEG L0 H0 BLOCK NX NY LEVEL T_END D_EFF MUS DMU I0 ETAMAX_SI RHO OUTPREFIX
  the domain is NX x NY square blocks of side BLOCK (m), each 2^LEVEL cells: dx = BLOCK/2^LEVEL.
Writes OUTPREFIX.profile (t [s], then the VOF thickness sum_j f dx of every column, m),
OUTPREFIX.stats (t, granular volume, share of it moving at >= 0.1 m/s, max speed where f > 0.5,
kinetic energy per unit width / rho), OUTPREFIX.log.
*/
#include "grid/multigrid.h"
#ifdef PFLOOR
/** Diagnostic variant (compiled with -DPFLOOR): granular.h with granudep's pressure floor
(rheology.pressure_floor: half_layer): the mu(I) law of every cell holding grains (f > 0.01) sees
p >= rho g cos(theta) dx/2. run_basilisk.sh makes granular_pfloor.h from granular.h with sed. */
double pfloor_coef = 0.;
#include "granular_pfloor.h"
#elif defined(BEDSTRESS)
/** Diagnostic variant (-DBEDSTRESS): the bed face's mu(I) viscosity at the bed's normal stress
(granudep's wall.bed_stress: bed); run_basilisk.sh makes granular_bed.h from granular.h. */
double bed_pn = 0.;
#include "granular_bed.h"
#else
#include "granular.h"
#endif

#define GSI 9.81
double TU;                     // time unit, s
double VU;                     // velocity unit, m/s
double theta, Lc, Hc, tend_si, etamax_si, rho_bulk;
double dt_out_si = 0.02;       // output interval, s
double rest_speed_si = 0.1;    // granudep's output.rest_speed
double rest_duration_si = 0.1; // granudep's output.rest_duration
double rest_since = -1.;
int started = 0;
char prefix[512];
FILE * fprof, * fstat;
face vector av[];

/** Boundary conditions: zero pressure at the top of the light fluid (granular.h's note: p at the
top = -RHOF * height, negligible), outflow there; no-slip bed and back wall (granudep's
`wall.slip: no_slip` applies to both); the down-slope end is Basilisk's default free-slip wall
(the deposit must stop short of it: checked by run_basilisk.sh). */
p[top] = dirichlet(0.);
pf[top] = dirichlet(0.);
u.n[top] = neumann(0.);
u.t[bottom] = dirichlet(0.);
u.t[left] = dirichlet(0.);

int main (int argc, char * argv[])
{
  if (argc < 16) {
    fprintf (stderr, "usage: column THETA_DEG L0 H0 BLOCK NX NY LEVEL T_END D_EFF MUS DMU I0 "
	     "ETAMAX_SI RHO OUTPREFIX\n");
    return 1;
  }
  theta = atof(argv[1])*pi/180.;
  Lc = atof(argv[2]); Hc = atof(argv[3]);
  double block = atof(argv[4]);
  int nx = atoi(argv[5]), ny = atoi(argv[6]), level = atoi(argv[7]);
  tend_si = atof(argv[8]);
  D = atof(argv[9]); mus = atof(argv[10]); dmu = atof(argv[11]); I0 = atof(argv[12]);
  etamax_si = atof(argv[13]); rho_bulk = atof(argv[14]);
  strncpy (prefix, argv[15], 500);
  TU = sqrt(1./GSI); VU = sqrt(GSI);
#ifdef PFLOOR
  pfloor_coef = 0.5*cos(theta);
#endif
#ifdef BEDSTRESS
  bed_pn = 0.5*cos(theta);
#endif
  etamax = etamax_si/(rho_bulk*sqrt(GSI));   // Pa s -> units of rho sqrt(g) (1 m)^1.5
  dimensions (nx = nx, ny = ny);
  size (block*nx);
  origin (0., 0.);
  init_grid (nx*(1 << level));
  DT = 2e-3/TU;                              // granudep's numerics.dt_max (2 ms)
  a = av;
  char name[600];
  sprintf (name, "%s.profile", prefix); fprof = fopen (name, "w");
  sprintf (name, "%s.stats", prefix); fstat = fopen (name, "w");
  fprintf (fstat, "# t_s vol_m2 moving_share max_speed_ms ke_m4s2\n");
  fprintf (stderr, "# dx = %g m, %d x %d cells, D = %g, mus = %g, dmu = %g, I0 = %g, etamax = %g (units) "
	   "= %g Pa s, TOLERANCE = %g, DT = %g s\n", L0/N, N, N*ny/nx, D, mus, dmu, I0, etamax,
	   etamax_si, TOLERANCE, DT*TU);
  run();
  fclose (fprof); fclose (fstat);
}

event init (t = 0) {
  fraction (f, min(Hc - y, Lc - x));
  foreach()
    p[] = f[]*cos(theta)*max(Hc - y, 0.);   // hydrostatic start, as granular_column.c
}

event acceleration (i++) {
  foreach_face(x) av.x[] += sin(theta);
  foreach_face(y) av.y[] -= cos(theta);
}

/** Output every dt_out_si: thickness per column, volume, moving share, rest rule. */
event output_profiles (t += 0.02/sqrt(1./GSI)) {
  double dx = L0/N;
  int nc = N;
  double * h = calloc (nc, sizeof(double));
  double vol = 0., mov = 0., vmax = 0., ke = 0.;
  foreach (serial) {
    int ic = (int) floor((x - X0)/dx);
    if (ic >= 0 && ic < nc) h[ic] += f[]*Delta;
    double sp = sqrt(sq(u.x[]) + sq(u.y[]))*VU;
    double dv = f[]*sq(Delta);
    vol += dv;
    if (sp >= rest_speed_si) mov += dv;
    if (f[] > 0.5 && sp > vmax) vmax = sp;
    ke += 0.5*dv*sq(sp);
  }
  double tsi = t*TU;
  fprintf (fprof, "%.5f", tsi);
  for (int k = 0; k < nc; k++) fprintf (fprof, " %.6g", h[k]);
  fprintf (fprof, "\n"); fflush (fprof);
  free (h);
  double share = vol > 0. ? mov/vol : 0.;
  fprintf (fstat, "%.5f %.8g %.6g %.6g %.6g\n", tsi, vol, share, vmax, ke);
  fflush (fstat);
  /** granudep's run-stop rule (output.rest_measure = max): every grain (here every cell more than
  half full) slower than rest_speed for rest_duration, after the flow has started. */
  if (vmax >= rest_speed_si) started = 1;
  if (started && vmax < rest_speed_si) {
    if (rest_since < 0.) rest_since = tsi;
    if (tsi - rest_since >= rest_duration_si - 1e-9) {
      fprintf (stderr, "# at rest since t = %g s (max speed %g m/s); stop at t = %g s\n",
	       rest_since, vmax, tsi);
      return 1;
    }
  }
  else
    rest_since = -1.;
  if (tsi >= tend_si - 1e-9) {
    fprintf (stderr, "# t_end = %g s reached (max speed %g m/s)\n", tsi, vmax);
    return 1;
  }
  return 0;
}

event logfile (i += 50) {
  fprintf (stderr, "t = %.4f s, i = %d, dt = %.3e s, mg p %d u %d\n", t*TU, i, dt*TU, mgp.i, mgu.i);
  fflush (stderr);
}

/** Field dumps (diagnostic): x y f u v p of every cell holding grains at 0.4, 0.8 and 1.2 s. */
event dump_fields (t = {0.4/sqrt(1./GSI), 0.8/sqrt(1./GSI), 1.2/sqrt(1./GSI)}) {
  char name[600];
  sprintf (name, "%s.field_t%.1f", prefix, t*TU);
  FILE * fp = fopen (name, "w");
  foreach (serial)
    if (f[] > 0.01)
      fprintf (fp, "%g %g %g %g %g %g\n", x, y, f[], u.x[]*VU, u.y[]*VU, p[]*rho_bulk*GSI);
  fclose (fp);
}

/** Keeps the run loop alive (Basilisk stops when no timed event is left); the run ends in
output_profiles (rest or T_END). */
event end (t = 1e4) {}
