//! The contracts between Rust and GLSL, read from the SPIR-V strata embeds (through `strata::vk::spirv`, the
//! walker the passes take their descriptor set layouts from): every member offset of the accumulation pass's push
//! constants and of the structs its buffers hold, the G-buffer and resolve passes' push constants and records,
//! that every stage of a pass declares the one layout the pass uses (`bindings()`, reflected) and that a binding
//! moved in GLSL alone no longer fits the Rust side's descriptor writes (`vk::descriptors::check_write`, which
//! every write goes through), and every compute shader's workgroup size against the sizes its dispatches divide
//! by (`strata::shaders::constants`). A change made on one side alone fails here.
use std::collections::HashMap;
use std::mem::offset_of;
use strata::render::accumulate_layout::{AccumulatePush, GpuCamera, GpuLight, GpuPrimitiveRecord, ResolvePush};
use strata::render::gbuffer_layout::{GBufferDraw, GBufferPush, GpuBump, GpuMaterial};
use strata::render::skinning::{GpuInfluence, SkinPush};
use strata::vk::pipeline::Binding;
use strata::vk::spirv::Module;

// The instructions and decorations the tests below patch (SPIR-V spec 3.32, 3.20, 3.6).
const OP_EXECUTION_MODE: u32 = 16;
const OP_EXECUTION_MODE_ID: u32 = 331;
const EXECUTION_MODE_LOCAL_SIZE: u32 = 17;
const EXECUTION_MODE_LOCAL_SIZE_ID: u32 = 38;
const OP_DECORATE: u32 = 71;
const OP_MEMBER_DECORATE: u32 = 72;
const DECORATION_BINDING: u32 = 33;
const DECORATION_OFFSET: u32 = 35;
const OP_CONTROL_BARRIER: u32 = 224;

fn parse(words: &[u32]) -> Module {
    strata::vk::spirv::parse(words).unwrap()
}

fn module(name: &str) -> Module {
    let (_, bytes) = strata::shaders::ALL.iter().find(|(n, _)| *n == name).unwrap_or_else(|| panic!("no {name}"));
    strata::vk::spirv::parse_bytes(bytes).unwrap()
}

/// The push-constant block, where the stage reads one (the optimizer drops it from a stage that does not).
fn push_constant_block(m: &Module) -> Option<u32> {
    let blocks = m.push_constant_blocks();
    assert!(blocks.len() <= 1, "more than one push-constant block");
    blocks.first().copied()
}

/// Binding number → (name, descriptor type) of what a module declares.
fn declared(m: &Module) -> HashMap<u32, (String, ash::vk::DescriptorType)> {
    m.descriptor_bindings().unwrap().into_iter().map(|(b, (name, kind, _))| (b, (name, kind))).collect()
}

/// `(field name, offset)` of each named field of a Rust struct: GLSL spells its members the same way.
macro_rules! of {
    ($t:ty; $($f:ident),*) => { vec![$((stringify!($f), offset_of!($t, $f))),*] };
}

/// Member name (as GLSL spells it) → offset in the Rust struct.
fn push_offsets() -> Vec<(&'static str, usize)> {
    let mut v = of!(AccumulatePush; eye, forward, background, width, height, sample_index, sample_count, sampler_kind,
        seed, light_offset, light_count, analytic_light_count, counter_slot, max_depth, total_light_power, ray_log,
        indirect, direct_light, alpha_moment, sabotage, shading_samples);
    v.push(("pad_end1", offset_of!(AccumulatePush, pad)));
    v
}

fn struct_offsets() -> Vec<(&'static str, Vec<(&'static str, usize)>)> {
    let mut record = of!(GpuPrimitiveRecord; positions, normals, uvs, indices, colors, dpdu, dpdv, material, uvs1);
    record.push(("pad0", offset_of!(GpuPrimitiveRecord, pad)));
    vec![
        (
            "GpuLight",
            of!(GpuLight; position_kind, axis_u, axis_v, normal, emission, cone, uv01, uv2_material, corner_alpha,
                uv1_01, uv1_2),
        ),
        ("GpuPrimitiveRecord", record),
        ("GpuCamera", of!(GpuCamera; world_from_camera, lens, range)),
        ("GpuMaterial", material_offsets()),
        ("Bump", of!(GpuBump; kind, amplitude, frequency, octaves, lacunarity, gain, derivative, epsilon)),
    ]
}

fn material_offsets() -> Vec<(&'static str, usize)> {
    let v = of!(GpuMaterial; base_color, emissive, metallic, roughness, transmission, ior, normal_scale,
        alpha_cutoff, alpha_mode, double_sided, base_color_texture, transmission_texture, normal_texture,
        emissive_texture, base_color_uv_rows, bump, metallic_roughness_texture, specular_texture,
        specular_color_texture, metallic_roughness_uv_rows, normal_uv_rows, emissive_uv_rows, transmission_uv_rows,
        specular_color, specular_uv_rows, specular_color_uv_rows, unlit, absorption, clearcoat, sheen,
        clearcoat_texture, clearcoat_roughness_texture, clearcoat_normal_texture, sheen_color_texture,
        sheen_roughness_texture, diffuse_transmission_texture, diffuse_transmission_color_texture, pad,
        clearcoat_uv_rows, clearcoat_roughness_uv_rows, clearcoat_normal_uv_rows, sheen_color_uv_rows,
        sheen_roughness_uv_rows, diffuse_transmission, diffuse_transmission_uv_rows,
        diffuse_transmission_color_uv_rows, iridescence, iridescence_texture, iridescence_thickness_texture, pad1,
        iridescence_uv_rows, iridescence_thickness_uv_rows, anisotropy, anisotropy_texture, pad2, anisotropy_uv_rows);
    v
}

/// The differences between a module's struct and the Rust one: empty when they agree member for member.
fn compare(m: &Module, id: u32, rust: &[(&str, usize)]) -> Vec<String> {
    let glsl = m.offsets(id);
    let mut problems = Vec::new();
    for (name, offset) in rust {
        match glsl.get(*name) {
            Some(&o) if o as usize == *offset => {}
            Some(&o) => problems.push(format!("{name}: GLSL offset {o}, Rust {offset}")),
            None => problems.push(format!("{name}: in Rust, not in GLSL")),
        }
    }
    for name in glsl.keys() {
        if !rust.iter().any(|(n, _)| n == name) {
            problems.push(format!("{name}: in GLSL, not in Rust"));
        }
    }
    problems
}

/// Every check of one module; the problems found.
fn check_module(m: &Module) -> Vec<String> {
    let mut problems: Vec<String> = m
        .push_constant_blocks()
        .first()
        .map(|&block| compare(m, block, &push_offsets()))
        .unwrap_or_default()
        .into_iter()
        .map(|p| format!("AccumulatePush.{p}"))
        .collect();
    for (name, rust) in struct_offsets() {
        // A stage that does not use a struct need not hold it (the hit shaders read no cameras).
        if let Some(id) = m.struct_named(name) {
            problems.extend(compare(m, id, &rust).into_iter().map(|p| format!("{name}.{p}")));
        }
    }
    problems.extend(binding_problems(m, &strata::render::accumulate::AccumulatePass::bindings(1).unwrap()));
    problems
}

/// The differences between the bindings a module declares and a pass's Rust list: each declared binding must be
/// in the list with the descriptor type it needs.
fn binding_problems(m: &Module, rust: &[Binding]) -> Vec<String> {
    let mut problems = Vec::new();
    for (binding, (name, kind)) in declared(m) {
        match rust.iter().find(|b| b.binding == binding) {
            Some(b) if b.kind == kind => {}
            Some(b) => problems.push(format!("binding {binding} ({name}): GLSL needs {kind:?}, Rust has {:?}", b.kind)),
            None => problems.push(format!("binding {binding} ({name}): in GLSL, not in Rust")),
        }
    }
    problems
}

#[test]
fn every_accumulation_stage_agrees_with_the_rust_layouts_and_bindings() {
    for name in ["accumulate.comp", "accumulate.rgen", "accumulate.rahit"] {
        let m = module(name);
        if name != "accumulate.rahit" {
            assert!(push_constant_block(&m).is_some(), "{name} reads no push constants");
        }
        let problems = check_module(&m);
        assert!(problems.is_empty(), "{name} disagrees with the Rust side:\n{}", problems.join("\n"));
    }
    // The compute shader uses every binding the Rust side declares.
    let used = declared(&module("accumulate.comp"));
    for b in strata::render::accumulate::AccumulatePass::bindings(1).unwrap() {
        assert!(
            used.contains_key(&b.binding),
            "binding {} is declared in Rust but not read by accumulate.comp",
            b.binding
        );
    }
}

/// The check can fail: the SPIR-V of accumulate.comp with one GLSL offset moved (what `layout(offset = …)` or a
/// reordered member in accumulate_layout.glsl would write) and one binding renumbered is caught, naming both.
#[test]
fn a_change_on_the_glsl_side_alone_is_caught() {
    let (_, bytes) = strata::shaders::ALL.iter().find(|(n, _)| *n == "accumulate.comp").unwrap();
    let mut words = ash::util::read_spv(&mut std::io::Cursor::new(bytes)).unwrap();
    let m = parse(&words);
    let block = push_constant_block(&m).expect("accumulate.comp reads push constants");
    let seed_member = (0..).find(|k| m.member_names[&(block, *k)] == "seed").unwrap();
    let camera_var = m
        .variables
        .iter()
        .find(|v| m.element(v.1).and_then(|e| m.names.get(&e)).map(String::as_str) == Some("Cameras"))
        .unwrap()
        .0;
    let mut i = 5;
    while i < words.len() {
        let (count, op) = ((words[i] >> 16) as usize, words[i] & 0xffff);
        let w = &mut words[i + 1..i + count];
        if op == OP_MEMBER_DECORATE && w[0] == block && w[1] == seed_member && w[2] == DECORATION_OFFSET {
            w[3] += 4;
        }
        if op == OP_DECORATE && w[0] == camera_var && w[1] == DECORATION_BINDING {
            w[2] = 12;
        }
        i += count;
    }
    let problems = check_module(&parse(&words)).join("\n");
    assert!(problems.contains("AccumulatePush.seed: GLSL offset 72, Rust 68"), "{problems}");
    assert!(problems.contains("binding 12 (Cameras): in GLSL, not in Rust"), "{problems}");
    // The layout the pass would take from that SPIR-V no longer fits the Rust side's write of the cameras.
    let layout = strata::vk::spirv::descriptor_bindings(&[("patched", bytemuck::cast_slice(&words))], 1).unwrap();
    let cameras = strata::shaders::constants::ACCUMULATE_BINDING_CAMERAS;
    let error = strata::vk::descriptors::check_write(&layout, cameras, ash::vk::DescriptorType::STORAGE_BUFFER, 1)
        .expect_err("the write of a moved binding must not fit");
    assert!(error.to_string().contains(&format!("declare no binding {cameras}")), "{error}");
}

/// The G-buffer's attachments: gbuffer.frag writes each at the location the Rust side creates it at
/// (`render::gbuffer_layout`), by name.
#[test]
fn the_gbuffer_pass_writes_each_attachment_where_the_rust_side_creates_it() {
    use strata::render::gbuffer_layout as g;
    const STORAGE_OUTPUT: u32 = 3;
    let m = module("gbuffer.frag");
    let outputs: HashMap<String, u32> = m
        .variables
        .iter()
        .filter(|v| v.2 == STORAGE_OUTPUT)
        .map(|v| (m.names[&v.0].clone(), m.locations[&v.0]))
        .collect();
    let rust = [
        ("out_position", g::attachment::POSITION),
        ("out_albedo", g::attachment::ALBEDO),
        ("out_material", g::attachment::MATERIAL),
        ("out_emission", g::attachment::EMISSION),
        ("out_specular", g::attachment::SPECULAR),
        ("out_surface_ids", g::attachment::SURFACE_IDS),
    ];
    assert_eq!(outputs.len(), g::ATTACHMENTS.len(), "{outputs:?}");
    for (name, index) in rust {
        assert_eq!(outputs.get(name).copied(), Some(index as u32), "{name}: {outputs:?}");
    }
}

/// The other passes' push constants and records: the G-buffer pass (both stages), the resolve pass, the skinning
/// pass.
#[test]
fn the_gbuffer_and_resolve_passes_agree_with_the_rust_layouts() {
    // The Rust struct pads to 16 bytes past the GLSL block's last member.
    let gbuffer_push = of!(GBufferPush; clip_from_world, view_z_row, draw, material);
    let mut draw = of!(GBufferDraw; world_from_object, normal_rows, instance, coverage_key);
    draw.push(("pad1", offset_of!(GBufferDraw, pad)));
    // The Rust struct pads to 16 bytes past the GLSL block's last member.
    let resolve = of!(ResolvePush; width, height, samples, exposure_scale, tone_map, transparent);
    let skin = of!(SkinPush; positions, normals, dpdu, dpdv, out_positions, out_normals, out_dpdu, out_dpdv,
        influences, joint_matrices, vertex_count, set_count, joint_count, pad);
    let influence = of!(GpuInfluence; joints01, joints23, weights);
    let mut problems = Vec::new();
    for (name, push, structs) in [
        ("gbuffer.vert", gbuffer_push.clone(), vec![("GBufferDraw", draw.clone())]),
        ("gbuffer.frag", gbuffer_push, vec![("GBufferDraw", draw), ("GpuMaterial", material_offsets())]),
        ("resolve.comp", resolve, vec![]),
        ("skin.comp", skin, vec![("GpuInfluence", influence)]),
    ] {
        let m = module(name);
        let block = push_constant_block(&m).unwrap_or_else(|| panic!("{name} reads no push constants"));
        problems.extend(compare(&m, block, &push).into_iter().map(|p| format!("{name} push constants: {p}")));
        for (s, rust) in structs {
            let id = m.struct_named(s).unwrap_or_else(|| panic!("{name} holds no {s}"));
            problems.extend(compare(&m, id, &rust).into_iter().map(|p| format!("{name} {s}.{p}")));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// Every other pass's descriptor bindings and every compute shader's workgroup size, against the Rust lists
/// (`bindings()` of each pass) and the sizes its dispatches divide by (`strata::shaders::constants`, read from
/// the same `shared_constants.glsl` the shaders include). Each pass's stages together use every binding its list
/// declares, so a binding dropped on the GLSL side alone is caught too.
#[test]
fn every_pass_declares_the_bindings_and_workgroup_size_the_rust_side_uses() {
    use strata::render::{gbuffer::GBufferPass, noise_probe::NoiseProbe, preview::PreviewPass};
    use strata::render::{ray_probe::RayProbe, resolve::ResolvePass};
    use strata::shaders::constants::*;
    // The sampling probe has no pass of its own: tests/sampling_gpu.rs lays it out from its SPIR-V too.
    let sampling_probe =
        strata::vk::spirv::descriptor_bindings(&[("sampling_probe.comp", strata::shaders::SAMPLING_PROBE_COMP)], 1)
            .unwrap();
    let probe = Some([PROBE_WORKGROUP_SIZE, 1, 1]);
    let passes: [(&[&str], Vec<Binding>, WorkgroupSize); 8] = [
        // Everything the skinning pass reads and writes is reached by device address: no bindings.
        (&["skin.comp"], Vec::new(), Some([SKIN_WORKGROUP_SIZE, 1, 1])),
        (&["gbuffer.vert", "gbuffer.frag"], GBufferPass::bindings(1).unwrap(), None),
        (&["preview.vert", "preview.frag"], PreviewPass::bindings(1).unwrap(), None),
        (&["resolve.comp"], ResolvePass::bindings().unwrap(), Some([RESOLVE_TILE_SIZE, RESOLVE_TILE_SIZE, 1])),
        (&["ray_probe.comp"], RayProbe::bindings().unwrap(), probe),
        (&["noise_probe.comp"], NoiseProbe::bindings().unwrap(), probe),
        (&["sampling_probe.comp"], sampling_probe, probe),
        (
            &["accumulate.comp"],
            strata::render::accumulate::AccumulatePass::bindings(1).unwrap(),
            Some([ACCUMULATE_TILE_SIZE, ACCUMULATE_TILE_SIZE, 1]),
        ),
    ];
    let mut problems = Vec::new();
    for (stages, rust, local_size) in passes {
        let modules: Vec<(&str, Module)> = stages.iter().map(|name| (*name, module(name))).collect();
        problems.extend(pass_problems(&modules, &rust, local_size));
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// How many workgroup barriers (OpControlBarrier) a module's instructions hold.
fn control_barriers(words: &[u32]) -> usize {
    let (mut i, mut found) = (5, 0);
    while i < words.len() {
        let count = (words[i] >> 16) as usize;
        found += usize::from(words[i] & 0xffff == OP_CONTROL_BARRIER);
        i += count.max(1);
    }
    found
}

/// The accumulation pass holds no workgroup barrier, either way it traces: lavapipe compiles a compute shader whose
/// module holds one (even one a specialization constant leaves unreached) so that each 8-lane vector can stop
/// there, which cost the pass about a quarter of its time (docs/performance.md, "No barrier in the accumulation
/// pass"). The check can fail: the same module with one barrier added is caught.
#[test]
fn the_accumulation_pass_holds_no_workgroup_barrier() {
    for name in ["accumulate.comp", "accumulate.rgen"] {
        let (_, bytes) = strata::shaders::ALL.iter().find(|(n, _)| *n == name).unwrap();
        let mut words = ash::util::read_spv(&mut std::io::Cursor::new(bytes)).unwrap();
        assert_eq!(control_barriers(&words), 0, "{name} holds a workgroup barrier");
        // OpControlBarrier %workgroup %workgroup %semantics: any ids will do for the count.
        words.extend([(4 << 16) | OP_CONTROL_BARRIER, 1, 1, 1]);
        assert_eq!(control_barriers(&words), 1, "{name}: an added barrier is not seen");
    }
}

/// A compute shader's workgroup size; None for graphics stages.
type WorkgroupSize = Option<[u32; 3]>;

/// The differences between one pass's stages and its Rust side: the bindings each stage declares, the bindings
/// none declares, and each stage's workgroup size.
fn pass_problems(stages: &[(&str, Module)], rust: &[Binding], local_size: WorkgroupSize) -> Vec<String> {
    let mut problems = Vec::new();
    let mut used = std::collections::HashSet::new();
    for (name, m) in stages {
        problems.extend(binding_problems(m, rust).into_iter().map(|p| format!("{name}: {p}")));
        used.extend(declared(m).into_keys());
        if m.workgroup_size() != local_size {
            problems.push(format!("{name}: workgroup size {:?} in GLSL, {local_size:?} in Rust", m.workgroup_size()));
        }
    }
    let names: Vec<&str> = stages.iter().map(|(name, _)| *name).collect();
    for b in rust {
        if !used.contains(&b.binding) {
            problems.push(format!("{}: binding {} is in Rust, not in GLSL", names.join(" + "), b.binding));
        }
    }
    problems
}

/// That check can fail: resolve.comp's SPIR-V with its workgroup widened and its display image renumbered is
/// caught, naming both.
#[test]
fn a_workgroup_size_or_binding_changed_on_the_glsl_side_alone_is_caught() {
    use strata::shaders::constants::*;
    let (_, bytes) = strata::shaders::ALL.iter().find(|(n, _)| *n == "resolve.comp").unwrap();
    let mut words = ash::util::read_spv(&mut std::io::Cursor::new(bytes)).unwrap();
    let m = parse(&words);
    let display = m.variables.iter().find(|v| m.names.get(&v.0).map(String::as_str) == Some("display")).unwrap().0;
    let mut i = 5;
    while i < words.len() {
        let (count, op) = ((words[i] >> 16) as usize, words[i] & 0xffff);
        let w = &mut words[i + 1..i + count];
        // The size as a literal: what glslang writes for a number in the layout (LocalSizeId's ids become it).
        if op == OP_EXECUTION_MODE_ID && w[1] == EXECUTION_MODE_LOCAL_SIZE_ID {
            words[i] = (count as u32) << 16 | OP_EXECUTION_MODE;
            let w = &mut words[i + 1..i + count];
            w[1] = EXECUTION_MODE_LOCAL_SIZE;
            w[2..5].copy_from_slice(&[16, RESOLVE_TILE_SIZE, 1]);
            i += count;
            continue;
        }
        if op == OP_DECORATE && w[0] == display && w[1] == DECORATION_BINDING {
            w[2] = 5;
        }
        i += count;
    }
    let changed = [("resolve.comp", parse(&words))];
    let problems = pass_problems(
        &changed,
        &strata::render::resolve::ResolvePass::bindings().unwrap(),
        Some([RESOLVE_TILE_SIZE, RESOLVE_TILE_SIZE, 1]),
    )
    .join("\n");
    assert!(
        problems.contains("resolve.comp: workgroup size Some([16, 8, 1]) in GLSL, Some([8, 8, 1]) in Rust"),
        "{problems}"
    );
    assert!(problems.contains("resolve.comp: binding 5 (display): in GLSL, not in Rust"), "{problems}");
    assert!(problems.contains("resolve.comp: binding 1 is in Rust, not in GLSL"), "{problems}");
}
