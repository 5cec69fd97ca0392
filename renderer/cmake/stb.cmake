# stb_image / stb_image_write from Debian's libstb-dev: the header-only library is also
# shipped compiled (libstb.so provides stbi_load, stbi_write_png, ...), so image.cpp
# includes the headers without defining STB_*_IMPLEMENTATION and links the library.
find_library(PBRT_STB_LIBRARY NAMES stb REQUIRED)
set(PBRT_EXTRA_LIBS ${PBRT_EXTRA_LIBS} ${PBRT_STB_LIBRARY})
