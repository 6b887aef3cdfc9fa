# The install layout, one definition for the whole tree.
#
# A prefix (`cmake --install build --prefix PREFIX`), for C++ applications and VTK modules built
# outside this tree:
#   PREFIX/lib/                   the libraries (RUNPATH $ORIGIN: the prefix can move)
#   PREFIX/include/vtkSVDAG/      the VTK classes' headers and the core's svdag/*.h
#   PREFIX/lib/cmake/vtkSVDAG/    vtkSVDAGConfig.cmake and the exported targets
#   PREFIX/bin/vtksvdag-render    the renderer's command line
#   PREFIX/python/vtksvdag/       the complete Python package (wrapped modules and pure Python)
# A wheel (scikit-build-core sets SKBUILD; pyproject.toml): the libraries and the wrapped modules
# together in vtksvdag/, beside the pure-Python package; no headers, CMake files or tools.
if(SKBUILD)
  set(_vtksvdag_wheel ON)
else()
  set(_vtksvdag_wheel OFF)
endif()

if(_vtksvdag_wheel)
  set(_vtksvdag_sdk_default OFF)
  set(_vtksvdag_python_default ".")
  set(VTKSVDAG_INSTALL_LIBDIR "vtksvdag")
else()
  set(_vtksvdag_sdk_default ON)
  set(_vtksvdag_python_default "python")
  set(VTKSVDAG_INSTALL_LIBDIR "${CMAKE_INSTALL_LIBDIR}")
endif()
option(VTKSVDAG_INSTALL_SDK
  "Install the headers, the CMake package and vtksvdag-render (off in a wheel)"
  ${_vtksvdag_sdk_default})
set(VTKSVDAG_PYTHON_DESTINATION "${_vtksvdag_python_default}" CACHE STRING
  "Directory (below the build tree and the install prefix) that holds the vtksvdag package")
set(VTKSVDAG_INSTALL_INCLUDEDIR "${CMAKE_INSTALL_INCLUDEDIR}/vtkSVDAG")
set(VTKSVDAG_INSTALL_CMAKEDIR "${VTKSVDAG_INSTALL_LIBDIR}/cmake/vtkSVDAG")

# Installed libraries find each other in their own directory; executables set their own RUNPATH.
set(CMAKE_INSTALL_RPATH "$ORIGIN")
