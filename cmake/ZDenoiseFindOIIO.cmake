# Find OpenImageIO through its CMake package. Debian's package names
# /usr/include/opencv4 among its include directories although OpenCV is an
# optional dependency that need not be installed; CMake refuses a missing
# include directory, so drop the ones that do not exist.
find_package(OpenImageIO CONFIG REQUIRED)
foreach(_zd_target OpenImageIO::OpenImageIO OpenImageIO::OpenImageIO_Util)
    if(TARGET ${_zd_target})
        get_target_property(_zd_dirs ${_zd_target} INTERFACE_INCLUDE_DIRECTORIES)
        if(_zd_dirs)
            set(_zd_kept)
            foreach(_zd_dir IN LISTS _zd_dirs)
                if(EXISTS "${_zd_dir}" OR _zd_dir MATCHES "^\\$<")
                    list(APPEND _zd_kept "${_zd_dir}")
                endif()
            endforeach()
            set_target_properties(${_zd_target} PROPERTIES
                INTERFACE_INCLUDE_DIRECTORIES "${_zd_kept}")
        endif()
    endif()
endforeach()
