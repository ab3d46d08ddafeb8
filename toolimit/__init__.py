"""toolimit: a robot learns to use a tool from one video demonstration.

The package is laid out as the pipeline of Zorina et al. (RA-L 2022):
``demos`` (i) -> ``scenes`` + ``align`` (ii) -> ``robots`` + ``trajopt`` (iii) -> ``learn`` (iv),
with ``deploy`` for export to a real robot, ``viz`` for meshcat views and rerun recordings and
``cli`` for the ``toolimit`` command.
"""

__version__ = "0.1.0"
