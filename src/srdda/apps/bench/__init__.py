"""Benchmarks shipped with srdda: the standard models (:mod:`.models`) and ``srdda bench`` (:mod:`.runner`)."""
