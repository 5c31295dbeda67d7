#version 330 compatibility
// Lab 20's texture shader: immediate-mode vertices (glVertex3f) and texture coordinates
// (glTexCoord2f) under the fixed-function matrices.
out vec2 texture_coordinate;

void main() {
    texture_coordinate = gl_MultiTexCoord0.st;
    gl_Position = gl_ModelViewProjectionMatrix * gl_Vertex;
}
