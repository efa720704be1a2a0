//! CPU twins of the shader math in `shaders/include/<same name>.glsl`: the same functions, tested equal to the
//! GPU, and what tests and any CPU baking use.
pub mod brdf;
pub mod bump;
pub mod dispersion;
pub mod environment;
pub mod ggx;
pub mod iridescence;
pub mod lens;
pub mod noise;
pub mod sampling;
pub mod sheen;
