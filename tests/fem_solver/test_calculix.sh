#!/usr/bin/env bash
# test_calculix — the FEM's static solve of a prestressed cable net against CalculiX, an
# independent nonlinear FEM code (Debian package calculix-ccx; .ci/run installs it).
# The nets of `make bench` (3 m square, edges fixed, E 1e9 Pa, A 1.26e-4 m², S_pre 1e6 Pa,
# 2 kN at the centre) with 11x11 and 41x41 nodes: fem_bench --static solves them with the
# FEM's own code, fem_bench --write-calculix writes the same net for CalculiX with each cable
# an axial spring (SPRINGA, geometrically nonlinear) whose force–elongation table is the
# cable's law N = A (E ε_GL + S_pre) l / L0. Checks: CalculiX completes; the centre
# deflections agree within 1e-4 relative (the table's linear interpolation and CalculiX's
# load stepping; measured with CalculiX on its default one thread 1.1e-5 at 11x11, 2.5e-5 at
# 41x41: 0.2374289 against 0.2374262 m, 0.1575474 against 0.1575435 m; on two threads, as
# make bench runs it, its last digits differ: 0.1575440 m); the largest strain stays inside
# the table's fine part (below 2.5 %; measured 1.4 % and 1.0 %). A third, independent
# computation of the 11x11 net: Newton's method in numpy on the same law (dense tangent, load
# in 10 increments) agrees within 1e-8 (measured: to the 9 printed digits). With half the
# prestress taken out of CalculiX's table the deflections differ by far more than the
# tolerance (checked too: the test can fail).
# The CalculiX checks are skipped (exit 77) where ccx is missing, after the numpy one.
. tests/e2e_lib.sh
bench=$NC_BUILD_TESTS/../bench/fem_bench
[ -x "$bench" ] || fail "$bench not built (make tests builds it)"

# the 11x11 net by an independent Newton solve (numpy; the same geometry, law and load)
read -r _ _ _ _ _ w11 _ < <("$bench" --static 11) || fail "fem_bench --static 11"
w_np=$("$PY" - <<'PY'
import numpy as np
n, side, EA, AS, P = 11, 3.0, 1e9 * 1.26e-4, 1e6 * 1.26e-4, 2000.0
h = side / (n - 1)
X = np.array([[i * h, j * h, 0.0] for j in range(n) for i in range(n)])
el = [(j * n + i, j * n + i + 1) for j in range(n) for i in range(n - 1)] + \
     [(j * n + i, (j + 1) * n + i) for j in range(n - 1) for i in range(n)]
free = np.repeat([0 < k % n < n - 1 and 0 < k // n < n - 1 for k in range(n * n)], 3)
c = 3 * (n // 2 * n + n // 2) + 2
u = np.zeros(3 * n * n)
for load in np.linspace(P / 10, P, 10):
    for _ in range(50):
        f, K = np.zeros(3 * n * n), np.zeros((3 * n * n, 3 * n * n))
        f[c] -= load
        for a, b in el:
            d = X[b] + u[3 * b:3 * b + 3] - X[a] - u[3 * a:3 * a + 3]
            s_tot = (EA * (d @ d - h * h) / (2 * h * h) + AS) / h
            if s_tot <= 0:
                continue
            kb = EA / h ** 3 * np.outer(d, d) + s_tot * np.eye(3)
            f[3 * a:3 * a + 3] += s_tot * d
            f[3 * b:3 * b + 3] -= s_tot * d
            for p, q, sg in ((a, a, 1), (b, b, 1), (a, b, -1), (b, a, -1)):
                K[3 * p:3 * p + 3, 3 * q:3 * q + 3] += sg * kb
        du = np.linalg.solve(K[np.ix_(free, free)], f[free])
        u[free] += du
        if np.abs(du).max() < 1e-13:
            break
print("%.12g" % -u[c])
PY
) || fail "the numpy Newton solve"
echo "11x11: numpy Newton $w_np m against netcouple $w11 m"
awk -v w="$w11" -v c="$w_np" 'BEGIN { d = (c - w) / w; exit !(d <= 1e-8 && d >= -1e-8) }' \
  || fail "11x11: netcouple $w11 m against the numpy Newton solve's $w_np m: not within 1e-8"

# the rest needs CalculiX
command -v ccx >/dev/null || { echo "SKIP: ccx not installed (apt-get install calculix-ccx)"; exit 77; }

ccx_centre() {  # ccx_centre NAME: runs CalculiX on $NC_TMP/NAME.inp, prints -u_z of the centre
  (cd "$NC_TMP" && ccx -i "$1" >"$1.log" 2>&1) || { tail -20 "$NC_TMP/$1.log" >&2; return 1; }
  awk 'NF == 4 && $1 ~ /^[0-9]+$/ { w = -$4 } END { print w }' "$NC_TMP/$1.dat"
}

for n in 11 41; do
  read -r _ _ _ _ iters w strain < <("$bench" --static "$n") || fail "fem_bench --static $n"
  "$bench" --write-calculix "$n" "$NC_TMP/net$n.inp" || fail "fem_bench --write-calculix $n"
  w_ccx=$(ccx_centre "net$n") || fail "ccx on net$n.inp"
  echo "${n}x$n: netcouple $w m ($iters Newton iterations), CalculiX $w_ccx m, largest strain $strain"
  awk -v w="$w" -v c="$w_ccx" 'BEGIN { d = (c - w) / w; exit !(d <= 1e-4 && d >= -1e-4 && w > 0.05) }' \
    || fail "${n}x$n: centre deflection $w m against CalculiX's $w_ccx m: not within 1e-4"
  awk -v s="$strain" 'BEGIN { exit !(s > 0 && s < 0.025) }' \
    || fail "${n}x$n: largest strain $strain outside the table's fine part (0-2.5 %)"
done

# the same 11x11 net with half the prestress force (A S_pre = 126 N, L0 = 0.3 m) taken out of
# CalculiX's table: the comparison must see the difference
awk '/^\*SPRING/ { t = 1; print; next } /^\*/ { t = 0 }
     t && NF { split($0, a, ","); l = a[2] + 0; f = a[1] - 63.0 * (1 + l / 0.3)
               printf "%.12e, %.12e\n", (a[1] > 0 && f > 0 ? f : 0), l; next }
     { print }' "$NC_TMP/net11.inp" > "$NC_TMP/halfprestress.inp"
w_half=$(ccx_centre halfprestress) || fail "ccx on halfprestress.inp"
echo "11x11 with half the prestress in CalculiX's table: $w_half m against $w11 m"
awk -v w="$w11" -v c="$w_half" 'BEGIN { d = (c - w) / w; exit !(d > 1e-3 || d < -1e-3) }' \
  || fail "a table with half the prestress still agrees within 1e-3: the comparison cannot fail"
echo "PASS"
