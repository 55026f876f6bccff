# tests/dfvc/extra.cmake - Eigen (double) reference checks of the DFVC core
# (Rubino 2020 discretisation and MPE): tests/dfvc/ref_*.cpp.
fd_add_eigen_refs(dfvc)
