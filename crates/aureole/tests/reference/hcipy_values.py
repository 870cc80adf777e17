"""Prints the hcipy values that crates/aureole/tests/reference.rs holds
aureole's aperture kernels to: encircled energy (the light within r px of
the centre, of a 201×201 kernel's total) of hcipy 0.7.1's Fraunhofer
propagation of our stop, by the reference of
crates/aureole-py/tests/test_diffraction_reference.py (pupil supersampled
8×, 6×6 sub-pixels per pixel), and its error estimate (the change with
1.5× the samples).

    target/pyvenv/bin/python crates/aureole/tests/reference/hcipy_values.py
"""

import pathlib
import sys

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).parents[3] / "aureole-py" / "tests"))
import test_diffraction_reference as ref  # noqa: E402

RADII = (1, 2, 3, 5, 8, 13, 21, 34, 55, 89)
CASES = [(7, 4.0, 1.0), (8, 8.0, 1.0), (0, 4.0, 1.0), (5, 32.0, 10.0)]

for blades, f_number, pitch in CASES:
    theirs = ref.encircled(ref.reference(blades, f_number, pitch))
    finer = ref.encircled(ref.reference(blades, f_number, pitch, pupil_samples=384, sub_pixels=9))
    values = ", ".join(f"({r}, {theirs[r - 1]:.6f})" for r in RADII)
    error = max(abs(theirs[r - 1] - finer[r - 1]) for r in RADII)
    print(f"// blades {blades}, f/{f_number:g}, pitch {pitch:g} µm: hcipy's own error ≤ {error:.1e}")
    print(f"({blades}, {f_number}, {pitch}, &[{values}]),")
