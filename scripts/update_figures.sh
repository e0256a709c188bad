#!/usr/bin/env bash
# Re-runs the paper's studies (scripts/study.py) and copies the figures shown in README.md
# to docs/figures/. Takes a few minutes on 2 cores. Usage: scripts/update_figures.sh
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out="$root/results/studies"
for study in timestep cable_impact restitution relaxation angled_net terrain special; do
  rm -rf "${out:?}/$study"
  "$root/scripts/study.py" "$study" --out "$out"
done
mkdir -p "$root/docs/figures"
cp "$out"/timestep/fig12_point_a_vs_static.png "$out"/timestep/fig13a_iterations_displacement.png \
   "$out"/timestep/fig13b_iterations_force.png "$out"/relaxation/fig14_relaxation.png \
   "$out"/restitution/fig16a_weak_cor.png "$out"/restitution/fig16b_strong_cor.png \
   "$out"/restitution/fig17_iterations_cor.png "$out"/cable_impact/fig9_point_a.png \
   "$out"/cable_impact/fig11_iterations.png "$out"/angled_net/fig20_angled_net.png \
   "$out"/terrain/fig22_terrain_net.png "$out"/terrain/fig21_terrain_curtain.png \
   "$out"/special/fig24_rock_cluster.png "$out"/special/fig25_net_sieve.png "$root/docs/figures/"
echo "figures copied to docs/figures/"
