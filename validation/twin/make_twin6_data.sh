#!/usr/bin/env bash
# The "measured" data of the six-parameter twin (twin6.yaml, README.md): one weld simulated
# by rsw at the truth of twin6_noise.py (all six Table I parameters inside their priors),
# on the coarse mesh of the studies' model.set (0.5 mm base, one level, 0.125 mm cells at
# the electrode rims, signals at every step, no field files); then twin6_noise.py takes its ten features as the forward model does and
# writes three noise realisations of three welds each. Writes validation/twin/data/:
# twin6_truth/ (the run), twin6_features_1.csv ... _3.csv, twin6_features_noise_free.csv,
# twin6_truth.json.
#   bash validation/twin/make_twin6_data.sh            # RSW=path/to/rsw to use another build
set -euo pipefail
cd "$(dirname "$0")/../.."
rsw=${RSW:-build/tools/rsw}
data=validation/twin/data
mkdir -p "$data"
sets=()
while IFS= read -r option; do sets+=(--set "$option"); done < <(/usr/bin/python3 validation/twin/twin6_noise.py --print-set)
OMP_NUM_THREADS=${OMP_NUM_THREADS:-1} "$rsw" simulate validation/paper_case/weld.yaml -q -o "$data/twin6_truth" \
  --set mesh.base_size=0.5mm --set mesh.weld_zone.levels=1 \
  --set 'mesh.refinement_boxes=[{r_min: 1.8 mm, r_max: 3.3 mm, z_min: 0.7 mm, z_max: 1.3 mm, levels: 2},
                                {r_min: 1.8 mm, r_max: 3.3 mm, z_min: -1.3 mm, z_max: -0.7 mm, levels: 2}]' \
  --set output.interval=0ms --set output.fields=false \
  "${sets[@]}"
/usr/bin/python3 validation/twin/twin6_noise.py "$data/twin6_truth" "$data" --rsw "$rsw"
