from setuptools import find_packages, setup

package_name = 'air_data_node'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
    ],
    install_requires=['setuptools'],
    extras_require={'test': ['pytest']},    # colcon test runs pytest (setup.cfg)
    zip_safe=True,
    maintainer='Transfer alignment testbed',
    maintainer_email='dev@transfer-alignment.invalid',
    description='Flush air-data sensor: five FADS port pressures from the aircraft truth; air-data truth and wind.',
    license='Apache-2.0',
    entry_points={
        'console_scripts': [
            'air_data_node = air_data_node.node:main'
        ],
    },
)
