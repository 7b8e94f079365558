"""Headless Project AirSim-compatible simulator server.

At the top: `server` (sockets, the current scene, its threads), `session` (a loaded scene), `cli` and
`__main__` (the command line), `errors` (the base exception of every room). Below them, rooms that import
only their own room or lower ones (`tests/test_layers.py` checks it): `robot` > `sensors` > `scene` >
`render` > `world` and `wire` (peers) > `motion`; each names in `__all__` what it offers the rest.
"""
