#ifdef BEDSTRESS
    /** granudep's wall.bed_stress = bed: the bed face's viscosity is the mu(I) viscosity of the
    first cell evaluated at the bed's normal stress p_b = p + rho g cos(theta) f Delta/2 (bed_pn =
    cos(theta)/2 in units rho = g = 1) instead of at the cell-centre pressure. */
    foreach_face(y)
      if (y < Y0 + Delta/2.) {
        double fm = (fa[] + fa[0,-1])/2.;
        double pb = max(p[], 0.) + bed_pn*f[]*Delta;
        double etab = mug;
        if (pb > 0. && f[] > 0.) {
          double dxx = u.x[1,0] - u.x[-1,0];
          double dyy = u.y[0,1] - u.y[0,-1];
          double dxy = (u.x[0,1] - u.x[0,-1] + u.y[1,0] - u.y[-1,0])/2.;
          double D2 = sq(dxx) + sq(dyy) + 2.*sq(dxy);
          if (D2 > 0.) {
            D2 = sqrt(2.*D2)/(2.*Delta);
            double In = D2*D/sqrt(pb);
            double muI = mus + dmu*In/(I0 + In);
            etab = min(max((Co + muI*pb)/D2, sqrt(D*D*D)), etamax);
          }
        }
        muv.y[] = fm*etab + (1. - fm)*mug;
      }
#endif
