"""The HIL fixtures are a pytest plugin (``pytest11`` entry point ``bridge_node.testing``):
a user's tests get ``hil_bench`` and ``hil_scenario`` without importing them, and a
conftest that also names the module in ``pytest_plugins`` does not register it twice."""
import subprocess
import sys

from conftest import REPO

USER_TEST = f'''
from bridge_node.testing import assert_scenario, PlayableScenario


def test_fixtures_without_an_import(hil_bench, hil_scenario):
    scenario = hil_scenario(r"{REPO / "config" / "scenarios" / "helm_response.toml"}")
    assert isinstance(scenario, PlayableScenario) and callable(hil_bench)
'''


def _pytest(folder) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(folder)],
                          capture_output=True, text=True, cwd=folder, timeout=120)


def test_a_users_tests_get_the_fixtures_from_the_entry_point(tmp_path):
    (tmp_path / "test_user.py").write_text(USER_TEST)
    r = _pytest(tmp_path)
    assert r.returncode == 0 and "1 passed" in r.stdout, r.stdout + r.stderr
    (tmp_path / "conftest.py").write_text('pytest_plugins = ["bridge_node.testing"]\n')
    r = _pytest(tmp_path)
    assert r.returncode == 0 and "1 passed" in r.stdout, r.stdout + r.stderr
