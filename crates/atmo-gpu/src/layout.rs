//! Parameter structs shared with WGSL: one definition each, `#[repr(C)]` and `Pod`,
//! with their field offsets listed so a test can hold them to naga's layout of the
//! shader's struct of the same name.

/// A struct whose layout a WGSL struct mirrors.
pub trait GpuStruct: bytemuck::Pod {
    /// The WGSL struct's name.
    const WGSL_NAME: &'static str;
    /// The shader files (under `shaders/`, separated by spaces) that, concatenated,
    /// declare it, as the pipeline's source concatenates them.
    const SHADER: &'static str;
    /// `(field, byte offset)` in declaration order, and the struct's size.
    fn fields() -> Vec<(&'static str, usize)>;
}

/// Declares a `#[repr(C)]` Pod struct mirrored by the WGSL struct `$name` in `$shader`,
/// and its [`GpuStruct`] layout. Fields must be 4-byte scalars, `[f32; 4]`-like arrays
/// or `[u32; 4]` (vec4 alignment); pad explicitly to 16 bytes, as WGSL uniform layout
/// does.
#[macro_export]
macro_rules! gpu_struct {
    ($(#[$meta:meta])* $vis:vis struct $name:ident in $shader:literal {
        $($(#[$fmeta:meta])* $field:ident : $ty:ty),* $(,)?
    }) => {
        $(#[$meta])*
        #[repr(C)]
        #[derive(Debug, Clone, Copy, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
        $vis struct $name {
            $($(#[$fmeta])* pub $field: $ty),*
        }

        impl $crate::layout::GpuStruct for $name {
            const WGSL_NAME: &'static str = stringify!($name);
            const SHADER: &'static str = $shader;
            fn fields() -> Vec<(&'static str, usize)> {
                vec![$((stringify!($field), std::mem::offset_of!($name, $field))),*]
            }
        }
    };
}
