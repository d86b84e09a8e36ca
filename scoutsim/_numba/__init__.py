"""How scoutsim compiles its core with Numba (private): the decorators (:mod:`.jit`), the
on-disk cache of the core (:mod:`.disk_cache`), and the compile-time replacements of some
of Numba's compiler steps, in place only while the core compiles (:mod:`.compile_steps`)."""
