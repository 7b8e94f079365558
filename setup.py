"""The wheel's build hook: the package gets the message space and the sample scenes at build time.

`build_py` builds radar_msgs/uuid_msgs from msg/ with Debian's genpy into airsim_mapper/ros/ (a catkin-style
space: share/ for rosmsg and rospack, lib/python3/dist-packages/ for the Python, setup.bash for the user's
shell; tools/gen_msgs.py), adds a .pth file that puts that Python on the installing environment's path, and
copies the sample scenes of sim_config/ into airsim_mapper/sim_config/. An editable install (`make setup`)
builds nothing here: `make setup` builds the checkout's own space at devel/.
"""

from __future__ import annotations

import importlib.util
import shutil
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

HERE = Path(__file__).resolve().parent


def _gen_msgs():
    spec = importlib.util.spec_from_file_location("airsim_mapper_gen_msgs", HERE / "tools" / "gen_msgs.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


class BuildWithMessages(build_py):
    def run(self) -> None:
        editable = getattr(self, "editable_mode", False)
        build_lib = Path(self.build_lib)
        if not editable:  # a module removed from the source must not linger in build/ and so in the wheel
            shutil.rmtree(build_lib / "airsim_mapper", ignore_errors=True)
        super().run()
        if editable:
            return
        gen_msgs = _gen_msgs()
        space = build_lib / "airsim_mapper" / "ros"
        gen_msgs.build_space(space)
        (build_lib / gen_msgs.PTH_NAME).write_text(f"airsim_mapper/ros/{gen_msgs.PYTHON_DIR.as_posix()}\n")
        scenes = build_lib / "airsim_mapper" / "sim_config"
        shutil.rmtree(scenes, ignore_errors=True)
        shutil.copytree(HERE / "sim_config", scenes)


setup(cmdclass={"build_py": BuildWithMessages})
