# tests/dfvc/extra.cmake - Eigen (double) reference checks of the DFVC core
# (Rubino 2020 discretisation and MPE; Varatharajan 2022 stator-flux-frame
# model and regulators): tests/dfvc/ref_*.cpp.
fd_add_eigen_refs(dfvc)
