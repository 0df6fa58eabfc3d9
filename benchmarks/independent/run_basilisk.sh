#!/usr/bin/env bash
# Independent continuum mu(I) solution: Basilisk + P.-Y. Lagree's sandbox
# granular.h, driven by our column.c, for T22-A70 and the flat glass-bead collapses with a no-slip
# bed. One command: builds Basilisk's qcc in a scratch folder outside the repository, compiles
# column.c, runs every case, writes the measures (benchmarks/independent/measures.py).
#
#   bash benchmarks/independent/run_basilisk.sh            # all cases (about 30 min of CPU)
#   CASES="flat05_4 flat05_2" bash benchmarks/independent/run_basilisk.sh   # a subset (names below)
#
# Environment:
#   BASILISK_SRC      Basilisk source tree with src/ (default: the comphy-lab/basilisk-C mirror's
#                     basilisk-source/, exported with git archive). Elsewhere get it from
#                     http://basilisk.fr (darcs clone http://basilisk.fr/basilisk, or the tarball
#                     http://basilisk.fr/basilisk/basilisk.tar.gz) and point BASILISK_SRC at it.
#   GRANULAR_H_DIR    folder holding sandbox/M1EMN/Exemples/granular.h (default: the same mirror's
#                     basilisk-wiki/; on basilisk.fr: http://basilisk.fr/sandbox/M1EMN/Exemples/granular.h)
#   BASILISK_SCRATCH  build and run folder (default /work/scratch/basilisk); nothing of Basilisk
#                     is copied into the repository.
#   NICE              nice level of the runs (default 10)
set -euo pipefail
HERE="$(cd "$(dirname "$0")" && pwd)"
REPO="$(cd "$HERE/../.." && pwd)"
MIRROR=/work/.mirror/comphy-lab+basilisk-C/repo
SCRATCH="${BASILISK_SCRATCH:-/work/scratch/basilisk}"
NICE="${NICE:-10}"
mkdir -p "$SCRATCH/runs"

# --- 1. Basilisk sources into the scratch folder ---------------------------------------------
if [ -z "${BASILISK_SRC:-}" ]; then
  if [ ! -d "$SCRATCH/basilisk-source/src" ]; then
    git -C "$MIRROR" archive HEAD basilisk-source/src basilisk-wiki/sandbox/M1EMN/Exemples/granular.h \
      | tar -x -C "$SCRATCH" 2>/dev/null || true     # (git archive also warns about darcs patch objects)
  fi
  BASILISK_SRC="$SCRATCH/basilisk-source"
  GRANULAR_H_DIR="${GRANULAR_H_DIR:-$SCRATCH/basilisk-wiki}"
  echo "basilisk mirror commit: $(git -C "$MIRROR" rev-parse HEAD)" > "$SCRATCH/runs/provenance.txt"
else
  echo "basilisk source: $BASILISK_SRC (user supplied)" > "$SCRATCH/runs/provenance.txt"
fi
GH="${GRANULAR_H_DIR:?set GRANULAR_H_DIR}/sandbox/M1EMN/Exemples"
test -f "$GH/granular.h" || { echo "granular.h not found in $GH" >&2; exit 1; }
echo "granular.h sha256: $(sha256sum "$GH/granular.h" | cut -d' ' -f1)" >> "$SCRATCH/runs/provenance.txt"

# --- 2. qcc (needs gcc, make, flex, bison, gawk: apt-get install -y flex bison gawk make) ------
export BASILISK="$BASILISK_SRC/src"
export PATH="$BASILISK:$PATH"
if [ ! -x "$BASILISK/qcc" ]; then
  ( cd "$BASILISK" && { [ -f config ] || cp config.gcc config; } \
    && make -C ast > "$SCRATCH/build_ast.log" 2>&1 && make qcc > "$SCRATCH/build_qcc.log" 2>&1 )
fi

# --- 3. our driver -----------------------------------------------------------------------------
BIN="$SCRATCH/column"
cp "$HERE/column.c" "$SCRATCH/column.c"     # qcc works in the folder of its input
# (qcc resolves every #include, also under #ifdef, so both headers must exist)
# diagnostic variant: granudep's pressure floor in the mu(I) law (column.c, PFLOOR)
sed -e 's/    if (p\[\] > 0.) {/    double pe = f[] > 0.01 ? max(p[], pfloor_coef*Delta) : p[];\n    if (pe > 0.) {/' \
    -e 's|double In = D2\*D/sqrt(p\[\]);|double In = D2*D/sqrt(pe);|' \
    -e 's|eta\[\] = max((Co + muI\*p\[\])/D2, etamin);|eta[] = max((Co + muI*pe)/D2, etamin);|' \
    "$GH/granular.h" > "$SCRATCH/granular_pfloor.h"
test "$(grep -c 'sqrt(pe)\|muI\*pe\|if (pe > 0.)' "$SCRATCH/granular_pfloor.h")" -ge 3 || { echo "granular_pfloor.h: sed did not apply" >&2; exit 1; }
# diagnostic variant: the bed face's mu(I) viscosity at the bed's normal stress
# (granudep's wall.bed_stress: bed): bed_stress_block.h inserted before granular.h's final boundary()
"${PYTHON:-python}" - "$GH/granular.h" "$HERE/bed_stress_block.h" "$SCRATCH/granular_bed.h" <<'PYEOF'
import sys
src, block, out = open(sys.argv[1]).read(), open(sys.argv[2]).read(), sys.argv[3]
anchor = "    boundary ({muv,alphav,rhov});\n}"
if src.count(anchor) != 1:
    sys.exit("granular_bed.h: the anchor of granular.h's properties event was not found")
open(out, "w").write(src.replace(anchor, block + anchor))
PYEOF
cp "$HERE/layer.c" "$SCRATCH/layer.c"
( cd "$SCRATCH" && qcc -O2 -Wall -I"$SCRATCH" -I"$GH" column.c -o "$BIN.tmp" -lm 2> "$SCRATCH/compile_column.log" \
    && mv "$BIN.tmp" "$BIN" )   # (a running binary is never overwritten in place)
( cd "$SCRATCH" && qcc -O2 -Wall -DPFLOOR -I"$SCRATCH" -I"$GH" column.c -o "$SCRATCH/column_pfloor.tmp" -lm \
    2> "$SCRATCH/compile_column_pfloor.log" && mv "$SCRATCH/column_pfloor.tmp" "$SCRATCH/column_pfloor" )
( cd "$SCRATCH" && qcc -O2 -Wall -DBEDSTRESS -I"$SCRATCH" -I"$GH" column.c -o "$SCRATCH/column_bed.tmp" -lm \
    2> "$SCRATCH/compile_column_bed.log" && mv "$SCRATCH/column_bed.tmp" "$SCRATCH/column_bed" )
( cd "$SCRATCH" && qcc -O2 -Wall -I"$SCRATCH" -I"$GH" layer.c -o "$SCRATCH/layer.tmp" -lm \
    2> "$SCRATCH/compile_layer.log" && mv "$SCRATCH/layer.tmp" "$SCRATCH/layer" )
( cd "$SCRATCH" && qcc -O2 -Wall -DBEDSTRESS -I"$SCRATCH" -I"$GH" layer.c -o "$SCRATCH/layer_bed.tmp" -lm \
    2> "$SCRATCH/compile_layer_bed.log" && mv "$SCRATCH/layer_bed.tmp" "$SCRATCH/layer_bed" )

# --- 4. granudep's material (Table 2 glass beads, as load_config('T22-A70') resolves it) -------
PY="${PYTHON:-python}"
read -r MUS DMU I0 DEFF ETAMAX RHO <<< "$("$PY" -c "
import math
from granudep.isph.config import load_config
c = load_config('T22-A70'); m = c.material
print(m.mu_s, m.mu_2 - m.mu_s, m.I0, m.d*math.sqrt(m.rho_s/m.rho), c.rheology.eta_max, m.rho)")"
echo "material: mu_s $MUS dmu $DMU I0 $I0 D_eff $DEFF eta_max $ETAMAX rho $RHO" | tee -a "$SCRATCH/runs/provenance.txt"

# --- 5. cases: name theta L0 H0 block nx ny level t_end(30 t_c) --------------------------------
# dx = block / 2^level. Cost (this 2-core machine, shared): ~30 us of CPU per cell and step at
# 4 mm, ~50 us at 2 mm (the viscous multigrid solve takes 15-30 iterations), so the ladders stop
# where one run costs minutes:
# T22-A70: 1.92 m x 0.16 m: 12 x 1 blocks of 0.16 m at dx = 20, 10 and 5 mm, 36 x 3 blocks of
#   0.0533 m at dx = 6.67 and 3.33 mm (T22 costs ~8-15 us per cell and step: dt is mostly DT).
# flats (L0 = 0.1 m): 0.384 m long, 0.064 m (a = 0.5) or 0.128 m (a = 1) high: dx = 8, 4, 2 mm.
ALL=(
  "flat05_4 0 0.1 0.05 0.064 6 1 4 2.142"
  "flat1_4  0 0.1 0.10 0.064 6 2 4 3.029"
  "flat05_2 0 0.1 0.05 0.064 6 1 5 2.142"
  "flat1_2  0 0.1 0.10 0.064 6 2 5 3.029"
  "flat05_8 0 0.1 0.05 0.064 6 1 3 2.142"
  "flat1_8  0 0.1 0.10 0.064 6 2 3 3.029"
  "T22_20   22 0.2 0.14 0.16 12 1 3 3.722"
  "T22_10   22 0.2 0.14 0.16 12 1 4 3.722"
  "T22_6.67 22 0.2 0.14 0.053333333333 36 3 3 3.722"
  "T22_5    22 0.2 0.14 0.16 12 1 5 3.722"
  "T22_3.33 22 0.2 0.14 0.053333333333 36 3 4 3.722"
  "T22pf_10   22 0.2 0.14 0.16 12 1 4 3.722"
  "T22pf_6.67 22 0.2 0.14 0.053333333333 36 3 3 3.722"
  "T22bed_5    22 0.2 0.14 0.16 12 1 5 3.722"
  "T22bed_3.33 22 0.2 0.14 0.053333333333 36 3 4 3.722"
)
# decelerating layers (benchmarks/decelerating_layer.py): name h(m) dx(m), 22 deg,
# Bagnold-shaped start at 1 m/s, 1.2 s; "layerbed_*" with the bed face at the bed's normal stress
LAYERS=(
  "layer_h4_dx2 0.004 0.002"   "layer_h6_dx2 0.006 0.002"   "layer_h10_dx2 0.01 0.002"  "layer_h20_dx2 0.02 0.002"
  "layer_h4_dx1 0.004 0.001"   "layer_h6_dx1 0.006 0.001"   "layer_h10_dx1 0.01 0.001"  "layer_h20_dx1 0.02 0.001"
)
# (0.5 mm was tried: layer_h4_dx0.5 lost its viscous multigrid convergence at
# t = 0.27 s, u.x residual 1e7 after 100 relaxations, and aborted in events.h; not run)
SEL="${CASES:-}"
for spec in "${ALL[@]}"; do
  read -r name th l0 h0 blk nx ny lev tend <<< "$spec"
  if [ -n "$SEL" ] && [[ " $SEL " != *" $name "* ]]; then continue; fi
  echo "$(date -u +%FT%TZ) run $name" | tee -a "$SCRATCH/runs/provenance.txt"
  exe="$BIN"; [[ "$name" == *pf_* ]] && exe="$SCRATCH/column_pfloor"   # diagnostic runs
  [[ "$name" == T22bed_* ]] && exe="$SCRATCH/column_bed"
  ( cd "$SCRATCH/runs" && /usr/bin/env time -f "$name cpu_user_s %U wall_s %e" -a -o cpu_times.txt \
      nice -n "$NICE" "$exe" "$th" "$l0" "$h0" "$blk" "$nx" "$ny" "$lev" "$tend" \
      "$DEFF" "$MUS" "$DMU" "$I0" "$ETAMAX" "$RHO" "$name" > "$name.log" 2>&1 ) \
    || echo "$name failed (rc $?): see $name.log" | tee -a "$SCRATCH/runs/provenance.txt"
done

for spec in "${LAYERS[@]}"; do
  read -r name h dl <<< "$spec"
  for variant in layer layerbed; do
    run="${name/layer/$variant}"
    if [ -n "$SEL" ] && [[ " $SEL " != *" $run "* ]] && [[ " $SEL " != *" layers "* ]]; then continue; fi
    exe="$SCRATCH/layer"; [ "$variant" = layerbed ] && exe="$SCRATCH/layer_bed"
    ( cd "$SCRATCH/runs" && /usr/bin/env time -f "$run cpu_user_s %U wall_s %e" -a -o cpu_times.txt \
        nice -n "$NICE" "$exe" 22 "$h" "$dl" 1.0 1.2 "$DEFF" "$MUS" "$DMU" "$I0" "$ETAMAX" "$RHO" "$run" \
        > "$run.log" 2>&1 ) || echo "$run failed (rc $?): see $run.log" | tee -a "$SCRATCH/runs/provenance.txt"
  done
done

# --- 6. measures -> docs/data/independent_basilisk*.csv ----------------------------------------
"$PY" "$HERE/measures.py" --runs "$SCRATCH/runs"
