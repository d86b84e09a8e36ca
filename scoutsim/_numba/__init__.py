"""How scoutsim compiles its core with Numba (private): the decorators and the on-disk
cache of the core (:mod:`.jit`), and the compile-time replacements of some of Numba's
compiler steps, applied only while the core compiles (:mod:`.compile_steps`)."""
