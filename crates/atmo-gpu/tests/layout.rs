//! Every parameter struct shared with WGSL against naga's layout of the shader's
//! struct of the same name: same fields, same order, same offsets, same size. A field
//! added on one side only, or a vec3 where the Rust side has 12 bytes, fails here.

use atmo_gpu::layout::GpuStruct;

fn check<T: GpuStruct>() {
    let source = atmo_gpu::wgsl::source(T::SHADER);
    let module = naga::front::wgsl::parse_str(&source)
        .unwrap_or_else(|e| panic!("{}: {}", T::SHADER, e.emit_to_string(&source)));
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).unwrap();
    let (handle, ty) = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(T::WGSL_NAME))
        .unwrap_or_else(|| panic!("{} declares no struct {}", T::SHADER, T::WGSL_NAME));
    let naga::TypeInner::Struct { members, span } = &ty.inner else {
        panic!("{} is not a struct in {}", T::WGSL_NAME, T::SHADER)
    };
    let wgsl: Vec<(&str, usize)> = members
        .iter()
        .map(|m| (m.name.as_deref().unwrap_or(""), m.offset as usize))
        .collect();
    assert_eq!(
        T::fields(),
        wgsl,
        "{} in {}: Rust fields vs WGSL members",
        T::WGSL_NAME,
        T::SHADER
    );
    assert_eq!(
        std::mem::size_of::<T>(),
        *span as usize,
        "{}: Rust size vs WGSL span",
        T::WGSL_NAME
    );
    assert_eq!(layouter[handle].size, *span);
}

#[test]
fn sky_structs_match_their_wgsl() {
    check::<atmo_gpu::sky::SkyMapParams>();
    check::<atmo_gpu::sky::SkyFrameParams>();
    check::<atmo_gpu::sky::ShellParams>();
    check::<atmo_gpu::sky::AerialParams>();
}

#[test]
fn the_display_struct_matches_its_wgsl() {
    check::<atmo_gpu::display::DisplayParams>();
}

#[test]
fn cloud_structs_match_their_wgsl() {
    check::<atmo_gpu::clouds::GpuParticle>();
    check::<atmo_gpu::clouds::BufferFrame>();
    check::<atmo_gpu::clouds::DrawParams>();
    check::<atmo_gpu::clouds::CompositeParams>();
    check::<atmo_gpu::clouds::SolveParams>();
}

#[test]
fn shafts_structs_match_their_wgsl() {
    check::<atmo_gpu::shafts::ShaftsParams>();
    check::<atmo_gpu::shafts::ShaftsFrameParams>();
    check::<atmo_gpu::shafts::GpuLight>();
}
