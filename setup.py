# Python module of the package (src/hidden_rooms), installed by catkin_python_setup(); do not run it directly.
from setuptools import setup
from catkin_pkg.python_setup import generate_distutils_setup

setup(**generate_distutils_setup(packages=["hidden_rooms"], package_dir={"": "src"}))
