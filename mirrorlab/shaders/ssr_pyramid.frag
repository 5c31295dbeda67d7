#version 330
// One level of screen-space reflections' nearest-depth pyramid (DepthPyramid): level 0
// the depth copy itself, each level above the least depth of the texels under it in the
// level below (the last texel of a row or column also taking the one left over where
// that level has an odd count). Drawn with ssr_composite.vert over the level's size.
uniform sampler2D source;  // the depth copy (level 0), or the pyramid itself
uniform int level;         // the level drawn
uniform ivec2 below;       // the size of the level below

out vec4 least;

void main() {
    ivec2 here = ivec2(gl_FragCoord.xy);
    if (level == 0) {
        least = vec4(texelFetch(source, here, 0).r);
        return;
    }
    ivec2 first = 2 * here;
    // where the level below has an odd count, its last texel goes to this level's last
    ivec2 last = min(first + 1, below - 1);
    last.x = (first.x + 3 == below.x) ? below.x - 1 : last.x;
    last.y = (first.y + 3 == below.y) ? below.y - 1 : last.y;
    float nearest = 1.0;
    for (int y = first.y; y <= last.y; ++y) {
        for (int x = first.x; x <= last.x; ++x) {
            // the level below is the texture's base level while this one is drawn
            nearest = min(nearest, texelFetch(source, ivec2(x, y), 0).r);
        }
    }
    least = vec4(nearest);
}
