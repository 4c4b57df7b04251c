"""mtaccuracy: the thin library behind the machine-tool accuracy compendium.

Units inside the library are millimetres and radians; every function that draws random
numbers takes a ``numpy.random.Generator`` or an explicit seed.
"""

__version__ = "0.1.0"
