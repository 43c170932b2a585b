"""Write the two-mass system of Bianchi et al. (2014), sec 4.1, Fig 5, as an axis description.

Layout (B): ground --C-- M1 --K-- M2 with M1 = 5000 kg (slide near the guide ways), K = 16e6
N/m, M2 = alpha M1 = 1500 kg (structure near the work piece). C is the viscous guide-way
friction between the slide and the ground: it is the [friction] of the description (viscous =
Copt = 4.912e5 N s/m, the paper's optimum), not part of the structure. The structure carries no
other damping (damping_ratio 0), so the only damping is the guide-way C as in the paper.

DOFs: ``pad1.x`` = slide X relative to the (rigid) ground, ``wp.x`` = work-piece X.
Run ``python models/two_mass_fig5/build.py --force`` to rewrite the files.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from servotune.structure.io import write_npz

HERE = Path(__file__).resolve().parent
M1, K, ALPHA = 5000.0, 16e6, 0.3
M2 = ALPHA * M1

AXIS_TOML = """\
# The two-mass system of Bianchi et al. (2014), sec 4.1 (Fig 5); built by build.py.

[axis]
name = "two_mass_fig5"
description = "Two-mass layout B of sec 4.1 (Fig 5): M1 = 5000 kg, K = 16e6 N/m, M2 = 1500 kg"

[structure]
file = "structure.npz"
modal_damping = 0.0             # the only damping is the guide-way damper C of [friction]

[friction]
pads = ["pad1.x"]               # the slide, relative to the ground
viscous = 4.912e5               # Copt of Fig 5 [N s/m]
"""


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=HERE)
    parser.add_argument("--force", action="store_true", help="overwrite existing files")
    args = parser.parse_args(argv)
    mass = np.diag([M1, M2])
    stiffness = K * np.array([[1.0, -1.0], [-1.0, 1.0]])
    toml = args.out / "axis.toml"
    if toml.exists() and not args.force:
        raise SystemExit(f"{toml} exists; pass --force to overwrite it")
    write_npz(args.out / "structure.npz", mass, stiffness, ["pad1.x", "wp.x"], force=args.force)
    toml.write_text(AXIS_TOML)


if __name__ == "__main__":
    main()
