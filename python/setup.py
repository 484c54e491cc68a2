"""The package's wheel holds the plugin's native library (built by build_backend/firemedium_build.py): marked so
the wheel is the platform's, not a pure-Python one."""

from setuptools import setup
from setuptools.dist import Distribution


class BinaryDistribution(Distribution):
    def has_ext_modules(self):
        return True


setup(distclass=BinaryDistribution)
