"""Visualisation: meshcat scenes and animations, rerun recordings, SVG figures (plots, charts, heat
maps, scenes in a plane; no plotting library). Never imported by stages."""
