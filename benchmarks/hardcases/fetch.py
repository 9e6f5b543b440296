"""Put SurfaceTopography's example files of the hard-case scene into ``benchmarks/hardcases/files``.

The five files come from SurfaceTopography's test suite (``test/file_format_examples``,
https://github.com/ContactEngineering/SurfaceTopography at the commit below, MIT licence). They
are downloaded from GitHub, or copied from a local folder holding them (``--from DIR``, e.g. a
clone of that repository's ``test/file_format_examples``); every file's SHA-256 is checked, so
the scene always solves the same bytes.

    python benchmarks/hardcases/fetch.py [--from DIR]
"""

from __future__ import annotations

import argparse
import hashlib
import shutil
import sys
import urllib.request
from pathlib import Path

COMMIT = "119cb66ade8917a0a62a878c82d459f959566760"
URL = f"https://raw.githubusercontent.com/ContactEngineering/SurfaceTopography/{COMMIT}/test/file_format_examples"
#: file name -> SHA-256 of its bytes at COMMIT
FILES = {
    "opd-1.opd": "e185389a17b2cdda5c750dfdbfe77e7b9a42df5534e1d2e34028b334003414fb",
    "sur-2.sur": "44f5c6c9aa48eef4b5f5814ad231b573a36725318b9ad0c15e019881d507cfde",
    "frt-2.frt": "e4de418521b4149549a750008c9127777e1ed645ab6ead87a24a404eb1a190ac",
    "mi-1.mi": "70bf0941496910760276a82d0e1824550399b7f16b6cf04edb8fd1209edb5d92",
    "x3p-2.x3p": "a53fbeb1764a6d0d2b22d189aebc1f7372a6d1430e5bbccc3cb2cc06616ce921",
}
HERE = Path(__file__).resolve().parent
DEST = HERE / "files"


def sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def fetch(name: str, source: Path | None) -> None:
    """Copy or download ``name`` into :data:`DEST` (atomically) and check its SHA-256."""
    target = DEST / name
    if target.is_file() and sha256(target) == FILES[name]:
        return
    tmp = target.with_suffix(target.suffix + ".part")
    if source is not None:
        shutil.copyfile(source / name, tmp)
    else:
        with urllib.request.urlopen(f"{URL}/{name}", timeout=60) as response, open(tmp, "wb") as out:
            shutil.copyfileobj(response, out)
    got = sha256(tmp)
    if got != FILES[name]:
        tmp.unlink()
        raise SystemExit(f"{name}: SHA-256 {got} is not the expected {FILES[name]} (SurfaceTopography @ {COMMIT})")
    tmp.replace(target)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--from", dest="source", type=Path, help="folder holding the files (else: download)")
    args = parser.parse_args(argv)
    DEST.mkdir(exist_ok=True)
    for name in FILES:
        try:
            fetch(name, args.source)
        except OSError as err:
            raise SystemExit(f"{name}: cannot {'copy' if args.source else 'download'} it ({err}); without network, "
                             "copy SurfaceTopography's test/file_format_examples here with --from DIR") from err
        print(f"{DEST / name}: ok")
    return 0


if __name__ == "__main__":
    sys.exit(main())
