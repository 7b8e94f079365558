"""Headless Project AirSim-compatible simulator server."""
