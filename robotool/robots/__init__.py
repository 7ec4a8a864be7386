"""Robots: the registry of embodiments and one package per robot."""
