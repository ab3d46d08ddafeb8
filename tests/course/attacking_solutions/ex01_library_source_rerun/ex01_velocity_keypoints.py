"""Attack: run the library's source again under another file name (`inspect.getsource` then
`exec`), so neither its code objects nor its file are the library's."""

import importlib
import inspect


def velocity_keypoints(demo, fraction=0.05):
    library = importlib.import_module("toolimit.align." + "keypoints")
    namespace = {"__name__": "my_keypoints"}
    exec(compile(inspect.getsource(library), "my_keypoints.py", "exec"), namespace)
    return namespace["velocity_" + "keypoints"](demo, fraction)
