from glob import glob

from setuptools import find_packages, setup

package_name = 'alignment_core'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
        # the repository's config/ (scenarios, node params) through the link config -> ../../config,
        # found by alignment_core.config.scenario.config_dir() in an install without the source
        ('share/' + package_name + '/config/scenarios', sorted(glob('config/scenarios/*.yaml'))),
        ('share/' + package_name + '/config/params', sorted(glob('config/params/*.yaml'))),
    ],
    install_requires=['setuptools'],
    extras_require={'test': ['pytest']},    # colcon test runs pytest (setup.cfg)
    zip_safe=True,
    maintainer='Transfer alignment testbed',
    maintainer_email='dev@transfer-alignment.invalid',
    description='Pure-Python physics and estimation library for shipboard transfer alignment (no ROS imports).',
    license='Apache-2.0',
    entry_points={
        'console_scripts': [

        ],
    },
)
