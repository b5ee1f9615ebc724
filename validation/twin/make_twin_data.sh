#!/usr/bin/env bash
# The "measured" data of the twin experiments (README.md): one weld simulated by rsw at
# known parameters — P1 = contact.electrode_sheet.htc_p1 = 0.02, every other value as in
# validation/paper_case/weld.yaml — on the coarse mesh (0.5 mm base, one level), with
# signals at every step and no field files (the settings of the studies' model.set),
# then Gaussian noise added with a fixed seed by add_noise.py (its docstring lists the
# noise). Writes validation/twin/data/: truth/ (the run), noise_free.csv,
# measured_1.csv ... measured_5.csv, twin_features.csv, twin_truth.json.
#   bash validation/twin/make_twin_data.sh            # RSW=path/to/rsw to use another build
set -euo pipefail
cd "$(dirname "$0")/../.."
rsw=${RSW:-build/tools/rsw}
data=validation/twin/data
mkdir -p "$data"
OMP_NUM_THREADS=${OMP_NUM_THREADS:-1} "$rsw" simulate validation/paper_case/weld.yaml -q -o "$data/truth" \
  --set mesh.base_size=0.5mm --set mesh.weld_zone.levels=1 \
  --set output.interval=0ms --set output.fields=false \
  --set contact.electrode_sheet.htc_p1=0.02
/usr/bin/python3 validation/twin/add_noise.py "$data/truth" "$data" --replicates 5 --seed 20250301 --rsw "$rsw"
