"""The version of srdda (one definition: the package, its results files and its reports read it here)."""
__version__ = "0.1.0"
