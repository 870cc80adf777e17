// The RGB that OpenEXR's own RGBA reader (Imf::RgbaInputFile) gives for a
// file, luminance/chroma ones reconstructed: the reference of
// tests/luminance_chroma.rs. Prints "WIDTH HEIGHT" on stderr and writes
// each pixel's R, G, B as half bits (little-endian u16) on stdout.
#include <OpenEXR/ImfArray.h>
#include <OpenEXR/ImfRgbaFile.h>
#include <cstdio>

int main(int argc, char **argv) {
    if (argc != 2) {
        fprintf(stderr, "usage: rgba_input FILE.exr\n");
        return 2;
    }
    Imf::RgbaInputFile file(argv[1]);
    Imath::Box2i window = file.dataWindow();
    int width = window.max.x - window.min.x + 1;
    int height = window.max.y - window.min.y + 1;
    Imf::Array2D<Imf::Rgba> pixels(height, width);
    file.setFrameBuffer(&pixels[0][0] - window.min.x - window.min.y * width, 1, width);
    file.readPixels(window.min.y, window.max.y);
    fprintf(stderr, "%d %d\n", width, height);
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
            unsigned short rgb[3] = {pixels[y][x].r.bits(), pixels[y][x].g.bits(),
                                     pixels[y][x].b.bits()};
            fwrite(rgb, sizeof(unsigned short), 3, stdout);
        }
    }
    return 0;
}
