#version 450 core
// Depth only: nothing to write but the depth the rasteriser computes.
void main() {}
