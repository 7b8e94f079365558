"""Converters between Project AirSim messages and ROS messages (pure functions, numpy fast paths).

`catalog` lists them (importable without ROS); `registry.get(name)` returns the implementation.
"""
