"""Visualisation: meshcat scenes and animations, rerun recordings. Never imported by stages."""
