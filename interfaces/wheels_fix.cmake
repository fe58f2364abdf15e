# The ROS wheels of the package registry export their Python typesupport targets with the include directory of
# the machine that built them (/opt/python/...), which no other machine has: CMake refuses such a target. This
# puts this machine's Python headers in its place, for every interface package the build depends on.
find_package(Python3 REQUIRED COMPONENTS Interpreter Development.Module)
function(fastep_fix_wheel_targets)
  foreach(dep ${ARGN})
    set(target ${dep}::${dep}__rosidl_generator_py)
    if(TARGET ${target})
      get_target_property(dirs ${target} INTERFACE_INCLUDE_DIRECTORIES)
      if(dirs)
        list(FILTER dirs EXCLUDE REGEX "^/opt/python/")
      else()
        set(dirs "")
      endif()
      list(APPEND dirs ${Python3_INCLUDE_DIRS})
      set_target_properties(${target} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${dirs}")
    endif()
  endforeach()
endfunction()
