"""`make test`'s expensive fixtures run once: its xdist groups hold (``--dist loadgroup``).

The demo run and every scene run of conftest.FAMILIES (grouped by this suite's conftest hook, also where
test_reader asks for the run through its family parameter) and a module's workflow
fixture (``pytestmark = xdist_group(...)``, e.g. test_real_files) each cost minutes. Spread over two
workers they ran twice: pytest 9.2 silently broke the groups (pytest-dev/pytest-xdist#1386), and a
mark added by a conftest hook that ran after xdist's was never seen. This runs pytest on a small
sample with this suite's conftest, as `make test` runs it, and reads which worker ran what.
"""
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("xdist")

SAMPLE = {
    # a module fixture named demo_run stands in for the session's (same name: the conftest hook groups by it)
    "test_demo_a.py": "import pytest\n\n@pytest.fixture(scope='module')\ndef demo_run():\n    return 1\n\n"
                      "def test_a1(demo_run): pass\n\ndef test_a2(demo_run): pass\n",
    "test_demo_b.py": "import pytest\n\n@pytest.fixture(scope='module')\ndef demo_run():\n    return 1\n\n"
                      "def test_b1(demo_run): pass\n\ndef test_b2(demo_run): pass\n",
    "test_module_group.py": "import pytest\n\npytestmark = [pytest.mark.xdist_group('m')]\n\n"
                            "def test_m1(): pass\n\ndef test_m2(): pass\n\ndef test_m3(): pass\n",
    "test_rest.py": "".join(f"def test_r{i}(): pass\n\n" for i in range(8)),
    # a scene run's fixture (lines_run) and a test over the families (test_reader's indirect family_run): each family's
    # test goes to its run's group
    "test_family.py": "import pytest\n\n@pytest.fixture(scope='module')\ndef lines_run():\n    return 1\n\n"
                      "@pytest.fixture\ndef family_run(request):\n    return request.param\n\n"
                      "def test_l1(lines_run): pass\n\n"
                      "@pytest.mark.parametrize('family_run', ['profiles', 'adhesion'], indirect=True)\n"
                      "def test_f(family_run): pass\n",
}
LINE = re.compile(r"\[(gw\d+)\].* PASSED (\S+?)::([\w\[\]-]+?)(@\w+)?\s*$")


@pytest.mark.slow  # over 3 s (make test-fast, 2026-12-03); run by make test
def test_the_demo_a_scene_run_and_a_modules_group_each_run_on_one_worker(tmp_path):
    for name, text in SAMPLE.items():
        (tmp_path / name).write_text(text)
    shutil.copy(Path(__file__).with_name("conftest.py"), tmp_path / "conftest.py")
    (tmp_path / "pytest.ini").write_text("[pytest]\n")
    res = subprocess.run([sys.executable, "-m", "pytest", "-v", "-n", "2", "--dist", "loadgroup",
                          "-p", "no:cacheprovider", str(tmp_path)], cwd=tmp_path, capture_output=True, text=True,
                         timeout=300)
    assert res.returncode == 0, res.stdout[-3000:] + res.stderr[-3000:]
    ran = {m.group(3): (m.group(1), m.group(4)) for m in map(LINE.search, res.stdout.splitlines()) if m}
    assert len(ran) == 18, res.stdout[-3000:]
    for tests, group in ((("test_a1", "test_a2", "test_b1", "test_b2"), "@demo_run"),
                         (("test_m1", "test_m2", "test_m3"), "@m"), (("test_l1", "test_f[profiles]"), "@lines_run"),
                         (("test_f[adhesion]",), "@adhesion_run")):
        assert {ran[t][1] for t in tests} == {group}, f"not in group {group}: {res.stdout[-3000:]}"
        assert len({ran[t][0] for t in tests}) == 1, f"group {group} split over workers: {res.stdout[-3000:]}"
