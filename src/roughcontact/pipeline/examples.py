"""Example topography files in instrument formats: the ``measured`` scene's inputs.

They stand in for measurements until you bring your own: generated rough surfaces
(:func:`roughcontact.surfaces.synthetic.generate_surface`), cut out of a larger periodic surface so
that they are not periodic, and written by SurfaceTopography's own writers in three
formats that exercise the reader's cases:

- ``ground-a.x3p``: ISO 25178-72 XML 3D surface profile; heights and size in metres
  (the scene's unit is micrometres, so the reader converts).
- ``ground-b.nc``: SurfaceTopography's NetCDF in micrometres, with a 6 x 7 block of
  undefined points (an instrument drop-out) for the reader to fill.
- ``ground-c.txt``: a plain text matrix, 160 x 128 points (not square), with no unit and no
  size: the scene supplies both (in nanometres).

``python -m roughcontact.pipeline.examples data/measured`` writes them; the files in
``data/measured/`` were made so. A test checks that the committed files hold what this
module writes (heights, sizes, units, undefined points).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from ..core.cli import input_errors
from ..surfaces.synthetic import generate_surface

#: Side of the example patches [um] and their spectral band (k_l, k_s of the parent surface).
LENGTH_UM = 100.0
_PARENT = {"k_l": 4.0, "k_s": 64.0, "hurst": 0.7, "rms_slope": 0.1}
#: The undefined block of ground-b: rows 40:46, columns 70:77.
UNDEFINED = (slice(40, 46), slice(70, 77))


def _patch(seed: int, rows: int, cols: int) -> np.ndarray:
    """A ``rows x cols`` non-periodic patch [um] of a 256 x 256 periodic surface of side 2 L."""
    parent = generate_surface(256, _PARENT["k_l"], _PARENT["k_s"], _PARENT["hurst"], seed,
                              length=2 * LENGTH_UM, rms_slope=_PARENT["rms_slope"])
    return np.ascontiguousarray(parent[:rows, :cols])


def example_heights() -> dict[str, tuple[np.ndarray, tuple[float, float]]]:
    """The three examples' heights [um] and physical sizes (Lx, Ly) [um], before writing."""
    dx = LENGTH_UM / 128
    return {
        "ground-a": (_patch(1, 128, 128), (LENGTH_UM, LENGTH_UM)),
        "ground-b": (_patch(2, 128, 128), (LENGTH_UM, LENGTH_UM)),
        "ground-c": (_patch(3, 160, 128), (160 * dx, LENGTH_UM)),
    }


def write_examples(folder: str | Path) -> dict[str, Path]:
    """Write the three example files into ``folder``; returns ``{name: path}``."""
    from SurfaceTopography import Topography

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    ex = example_heights()
    paths = {name: folder / f"{name}.{ext}" for name, ext in (("ground-a", "x3p"), ("ground-b", "nc"),
                                                               ("ground-c", "txt"))}
    h, size = ex["ground-a"]
    Topography(h * 1e-6, (size[0] * 1e-6, size[1] * 1e-6), unit="m", periodic=False).to_x3p(str(paths["ground-a"]))
    h, size = ex["ground-b"]
    mask = np.zeros(h.shape, dtype=bool)
    mask[UNDEFINED] = True
    Topography(np.ma.masked_array(h, mask=mask), size, unit="um", periodic=False).to_netcdf(str(paths["ground-b"]))
    h, _ = ex["ground-c"]
    np.savetxt(paths["ground-c"], h * 1e3, fmt="%.9e")  # nanometres, no header: no unit, no size
    return paths


def main(argv=None) -> None:
    """``python -m roughcontact.pipeline.examples FOLDER``: write the example files into FOLDER (made if missing)."""
    ap = argparse.ArgumentParser(prog="python -m roughcontact.pipeline.examples", description=main.__doc__)
    ap.add_argument("folder", type=Path, help="where to write them, e.g. data/measured")
    args = ap.parse_args(argv)
    with input_errors(ap):
        if args.folder.exists() and not args.folder.is_dir():
            raise ValueError(f"{args.folder}: is a file, not a folder; give the folder to write the examples into")
        written = write_examples(args.folder)
    for name, path in written.items():
        print(f"{name}: {path}")


if __name__ == "__main__":
    main()
