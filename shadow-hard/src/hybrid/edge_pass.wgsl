// The edge pass: clip-space quads into a depth target, which keeps the nearest edge per texel.

@vertex fn vs_edge(@location(0) p: vec4<f32>) -> @builtin(position) vec4<f32> { return p; }
