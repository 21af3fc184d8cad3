// The Rust type of each GLSL type the interface declaration (src/gpu/shaders/interface.rs) may
// use; `include!`d by both of its expansions, build.rs's and the library's.
#[rustfmt::skip]
macro_rules! rust_type {
    (float) => { f32 };
    (int) => { i32 };
    (uint) => { u32 };
    (vec3) => { [f32; 3] };
    (vec4) => { [f32; 4] };
    (ivec4) => { [i32; 4] };
    (uvec4) => { [u32; 4] };
    (mat4) => { [f32; 16] };
    ([$element:tt; $len:expr]) => { [rust_type!($element); $len] };
    ($block:ident) => { $block };
}
