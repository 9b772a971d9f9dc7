"""Only what pyproject.toml cannot say: a regular install also puts pymunk_bot-gymnasium.pth in
site-packages, the start-up hook that registers pymunk_bot/Navigation-v0 with Gymnasium 1.x
(which loads no plugin entry points; see _pymunk_bot_gymnasium.py and docs/learning.md)."""
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

HOOK = "pymunk_bot-gymnasium.pth"


class BuildPyWithHook(build_py):
    """build_py, plus the .pth at the top of the wheel (a .pth works only in site-packages)."""

    def run(self) -> None:
        super().run()
        self.copy_file(HOOK, str(Path(self.build_lib) / HOOK))

    def get_outputs(self, include_bytecode: bool = True) -> list[str]:
        return [*super().get_outputs(include_bytecode), str(Path(self.build_lib) / HOOK)]


setup(cmdclass={"build_py": BuildPyWithHook})
