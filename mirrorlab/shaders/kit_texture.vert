#version 330 compatibility
// Lab 20's texture shader: immediate-mode vertices (glVertex3f) and texture coordinates
// (glTexCoord2f) under the fixed-function matrices. Written for the compatibility
// profile's immediate mode; on a core context the trusted side translates its built-ins
// (labs/trusted/compat_glsl.py) and feeds them from its own glBegin/glEnd.
out vec2 texture_coordinate;

void main() {
    texture_coordinate = gl_MultiTexCoord0.st;
    gl_Position = gl_ModelViewProjectionMatrix * gl_Vertex;
}
