"""The documentation's reference pages are made from the code: a key added to a settings
model is in the config reference with its type, default, range and description, with no
edit to the docs; and the site builds strictly (no broken link, every page in the nav)."""
import subprocess
import sys

from conftest import REPO
from pydantic import Field

from bridge_node.node.config import NodeConfig
from bridge_node.reference.config_reference import config_reference
from bridge_node.reference.pages import REFERENCE_PAGES
from sim_core.params import Params


class ToySettings(Params):
    """A section a new feature would add."""

    floe_spin_limit: float = Field(2.5, ge=0.0, le=9.0, description="rad/s a floe may spin at most")


class ExtendedConfig(NodeConfig):
    toy: ToySettings = ToySettings()


def test_a_key_added_to_a_settings_model_is_in_the_generated_reference():
    page = config_reference(ExtendedConfig, "Config reference")
    assert "## `[toy]`" in page and "A section a new feature would add." in page
    [row] = [line for line in page.splitlines() if "`floe_spin_limit`" in line]
    assert "number" in row and "`2.5`" in row and ">= 0.0, <= 9.0" in row and "rad/s a floe may spin at most" in row
    assert "floe_spin_limit" not in config_reference(NodeConfig, "Config reference")


def test_every_reference_page_is_made_and_names_what_the_code_has():
    pages = {path: make() for path, make in REFERENCE_PAGES.items()}
    assert "`start_speed_kn`" in pages["reference/config.md"] and "## `[[links]]" not in pages["reference/config.md"]
    assert "## `icebridge ctl`" in pages["reference/cli.md"] and "sensor-failure" in pages["reference/cli.md"]
    assert "| `RMC` | `GP` |" in pages["reference/interfaces.md"] and "PGN 129025" in pages["reference/interfaces.md"]
    assert "`fix_valid`" in pages["reference/stream.md"] and "`ice_load`" in pages["reference/stream.md"]



def test_the_site_builds_strictly(tmp_path):
    built = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path / "site")],
                           cwd=REPO, capture_output=True, text=True, timeout=240)
    assert built.returncode == 0, built.stderr[-3000:]
    config_page = (tmp_path / "site" / "reference" / "config" / "index.html").read_text()
    assert "start_speed_kn" in config_page
