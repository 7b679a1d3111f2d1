# The Debian package (issue 16): `cd build && cpack -G DEB` makes
# build/package/orthomech_<version>_amd64.deb of the install tree (cmake/install.cmake) under /usr.
# Included after python/ (the Python version of the module is a Recommends).
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME orthomech)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_CONTACT "orthomech maintainers <orthomech@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
    "planar linkage analysis with the mass-orthogonal projection method")
string(CONCAT CPACK_PACKAGE_DESCRIPTION
       "Command-line tool, C++ library (headers, CMake package, pkg-config) and Python module "
       "for the kinematics, kinetostatics and dynamics of planar linkages.")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)  # orthomech_<version>_amd64.deb
set(CPACK_DEBIAN_PACKAGE_SECTION science)
# Runtime dependencies from the ELF files (dpkg-shlibdeps: Ipopt, yaml-cpp, SQLite, ...); the
# package's own liborthomech (the Python module links it) is found in the package itself.
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS_PRIVATE_DIRS ${PROJECT_BINARY_DIR})
# Cairo and fontconfig are opened when a picture is first drawn (src/io/shared_library.hpp), so no
# ELF file names them: declared here. Open MPI likewise for `sweep` under mpirun, which needs
# Open MPI installed anyway: recommended.
set(CPACK_DEBIAN_PACKAGE_DEPENDS "libcairo2, libfontconfig1")
# The C++ headers need Eigen; the Python module needs the Python 3 it was built for and NumPy.
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "libeigen3-dev, python3-numpy, libopenmpi3")
if(ORTHOMECH_PYTHON_VERSION)
  string(APPEND CPACK_DEBIAN_PACKAGE_RECOMMENDS
         ", python3 (>= ${ORTHOMECH_PYTHON_VERSION}), python3 (<< ${ORTHOMECH_PYTHON_NEXT})")
endif()
set(CPACK_DEBIAN_COMPRESSION_TYPE gzip)
set(CPACK_OUTPUT_FILE_PREFIX ${PROJECT_BINARY_DIR}/package)
include(CPack)
