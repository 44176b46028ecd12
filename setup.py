"""The Python module ladar_perception: the ROS-free core from NumPy.

catkin reads the package layout from here (catkin_python_setup); `pip install .` builds the
compiled module _core by driving CMake with -DLADAR_CORE_ONLY=ON (the core and the module, no
ROS), with the cmake, pybind11 and libraries of the Debian archive.
"""
import os
import re
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = os.path.dirname(os.path.abspath(__file__))


def package_version():
    with open(os.path.join(ROOT, "package.xml")) as f:
        return re.search(r"<version>([^<]+)</version>", f.read()).group(1)


class CMakeExtension(Extension):
    def __init__(self, name):
        super().__init__(name, sources=[])


class CMakeBuild(build_ext):
    """Configures the core-only CMake project and builds the module into the package."""

    def build_extension(self, ext):
        out_dir = os.path.dirname(os.path.abspath(self.get_ext_fullpath(ext.name)))
        build_dir = os.path.abspath(os.path.join(self.build_temp, "cmake"))
        os.makedirs(build_dir, exist_ok=True)
        jobs = os.environ.get("LADAR_PIP_JOBS", str(os.cpu_count() or 2))
        subprocess.check_call([
            "cmake", "-S", ROOT, "-B", build_dir, "-DLADAR_CORE_ONLY=ON",
            "-DCMAKE_BUILD_TYPE=Release", "-DPYTHON_EXECUTABLE=" + sys.executable,
            "-DLADAR_PYTHON_OUTPUT_DIR=" + out_dir])
        subprocess.check_call(["cmake", "--build", build_dir, "--target", "ladar_perception_python",
                               "--", "-j" + jobs])


setup(
    name="ladar_perception",
    version=package_version(),
    description="Vertical-scan ground extraction for 3D ladars (Foote 2008), the ladar simulator "
                "and the SemanticKITTI scorer, from NumPy",
    license="BSD-3-Clause",
    packages=["ladar_perception"],
    package_dir={"": "python"},
    ext_modules=[CMakeExtension("ladar_perception._core")],
    cmdclass={"build_ext": CMakeBuild},
    install_requires=["numpy"],
    python_requires=">=3.8",
)
