# tests/core/extra.cmake - Eigen (double) reference checks of the core's
# flux map: tests/core/ref_*.cpp.
fd_add_eigen_refs(core)
