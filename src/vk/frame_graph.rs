//! Passes that say what they read and write, and the barriers between them (docs/architecture.md, "One frame").
//!
//! A pass declares each resource it touches — an image with the layout it needs, a buffer, or memory the graph
//! knows only by a name (acceleration structures, which builds and ray queries reach through device addresses)
//! — with the stages and accesses it uses it with. The graph remembers, per resource, its layout, its last write
//! and the reads since, and records before the pass one `vkCmdPipelineBarrier2` holding what the pass's uses need
//! (Vulkan 1.3 §7.6, "Pipeline Barriers"): a layout transition; a memory dependency after the last write, for a
//! read that has not yet seen it or for another write; an execution dependency after the reads since, for a
//! write. The passes themselves record only their work. kajiya's render graph is the model (a pass's
//! `read`/`write` decide its synchronization); this one records as passes are added, in their order, because a
//! frame's passes are a fixed sequence with nothing to reorder or cull.
use super::commands::{labelled, recorded, Access};
use super::device::Device;
use super::memory::{Buffer, Image};
use ash::vk;
use std::collections::HashMap;
use std::sync::Arc;

/// What a use names: the graph tracks each by its handle (an image the resolve writes over is the same resource
/// as the G-buffer attachment it aliases) or, for memory, by its name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
enum Key {
    Image(vk::Image),
    Buffer(vk::Buffer),
    Memory(&'static str),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Read,
    /// A write that keeps what the resource held (a read-modify-write, a partial write).
    Write,
    /// A write over all of it: its old contents are not needed (an image's old layout may be `UNDEFINED`).
    Overwrite,
}

/// One resource a pass touches, and how.
#[derive(Clone, Copy)]
pub struct Use {
    key: Key,
    range: Option<vk::ImageSubresourceRange>,
    kind: Kind,
    layout: vk::ImageLayout,
    access: Access,
}

impl Use {
    /// `image` read in `layout` by `access`.
    pub fn read_image(image: &Image, layout: vk::ImageLayout, access: Access) -> Self {
        Self::on_image(image, Kind::Read, layout, access)
    }

    /// `image` written in `layout` by `access`, what it held kept.
    pub fn write_image(image: &Image, layout: vk::ImageLayout, access: Access) -> Self {
        Self::on_image(image, Kind::Write, layout, access)
    }

    /// All of `image` written in `layout` by `access`: what it held is discarded.
    pub fn overwrite_image(image: &Image, layout: vk::ImageLayout, access: Access) -> Self {
        Self::on_image(image, Kind::Overwrite, layout, access)
    }

    pub fn read_buffer(buffer: &Buffer, access: Access) -> Self {
        Self::on_buffer(buffer, Kind::Read, access)
    }

    pub fn write_buffer(buffer: &Buffer, access: Access) -> Self {
        Self::on_buffer(buffer, Kind::Write, access)
    }

    /// Memory the graph knows by `name` alone, read by `access` (its barriers are global memory barriers).
    pub fn read_memory(name: &'static str, access: Access) -> Self {
        Self::on_memory(name, Kind::Read, access)
    }

    pub fn write_memory(name: &'static str, access: Access) -> Self {
        Self::on_memory(name, Kind::Write, access)
    }

    fn on_image(image: &Image, kind: Kind, layout: vk::ImageLayout, access: Access) -> Self {
        Self { key: Key::Image(image.raw), range: Some(image.subresource_range()), kind, layout, access }
    }

    fn on_buffer(buffer: &Buffer, kind: Kind, access: Access) -> Self {
        Self { key: Key::Buffer(buffer.raw), range: None, kind, layout: vk::ImageLayout::UNDEFINED, access }
    }

    fn on_memory(name: &'static str, kind: Kind, access: Access) -> Self {
        Self { key: Key::Memory(name), range: None, kind, layout: vk::ImageLayout::UNDEFINED, access }
    }
}

/// What the graph knows of one resource.
#[derive(Debug, Clone, Copy)]
struct State {
    layout: vk::ImageLayout,
    /// The last write (or layout transition, as the stages after it), which later uses must wait for.
    written: Access,
    /// What the last write has been made visible to.
    visible: Access,
    /// The reads since the last write, which a write must wait for.
    reads: Access,
}

impl Default for State {
    fn default() -> Self {
        Self { layout: vk::ImageLayout::UNDEFINED, written: Access::NONE, visible: Access::NONE, reads: Access::NONE }
    }
}

/// One barrier a use needs: from, to, and for an image the layouts.
struct Dependency {
    from: Access,
    to: Access,
    layouts: Option<(vk::ImageLayout, vk::ImageLayout)>,
}

impl State {
    /// Updates the state for `usage` and returns the barrier it needs first, if any.
    fn apply(&mut self, usage: &Use) -> Option<Dependency> {
        let is_image = usage.range.is_some();
        match usage.kind {
            Kind::Read => {
                if is_image && usage.layout != self.layout {
                    let layouts = Some((self.layout, usage.layout));
                    let from = union(self.written, self.reads);
                    // The transition wrote the image: later reads in other stages wait for the stages after
                    // it; its writes are available once this barrier is done.
                    *self = State {
                        layout: usage.layout,
                        written: Access { stage: usage.access.stage, access: vk::AccessFlags2::NONE },
                        visible: usage.access,
                        reads: usage.access,
                    };
                    return Some(Dependency { from, to: usage.access, layouts });
                }
                self.reads = union(self.reads, usage.access);
                if self.written == Access::NONE || covers(self.visible, usage.access) {
                    return None;
                }
                self.visible = union(self.visible, usage.access);
                Some(Dependency { from: self.written, to: usage.access, layouts: None })
            }
            Kind::Write | Kind::Overwrite => {
                let from = union(self.written, self.reads);
                let old = if usage.kind == Kind::Overwrite { vk::ImageLayout::UNDEFINED } else { self.layout };
                let transition = is_image && (usage.kind == Kind::Overwrite || usage.layout != self.layout);
                *self =
                    State { layout: usage.layout, written: usage.access, visible: Access::NONE, reads: Access::NONE };
                (transition || from != Access::NONE).then_some(Dependency {
                    from,
                    to: usage.access,
                    layouts: transition.then_some((old, usage.layout)),
                })
            }
        }
    }
}

fn union(a: Access, b: Access) -> Access {
    Access { stage: a.stage | b.stage, access: a.access | b.access }
}

fn covers(a: Access, b: Access) -> bool {
    a.stage.contains(b.stage) && a.access.contains(b.access)
}

/// The state of every resource a sequence of passes touched, and the recording of their barriers. Keep one for
/// all the command buffers of a frame: the state carries over from one submission to the next.
pub struct FrameGraph {
    device: Arc<Device>,
    states: HashMap<Key, State>,
}

impl FrameGraph {
    /// A graph that has seen nothing: each resource's first use finds it undefined and unused.
    pub fn new(device: &Arc<Device>) -> Self {
        Self { device: device.clone(), states: HashMap::new() }
    }

    /// Records into `cmd` the barrier `uses` need, then `record` (the pass's work) in a region labelled `label`.
    pub fn pass<R>(&mut self, cmd: vk::CommandBuffer, label: &str, uses: &[Use], record: impl FnOnce() -> R) -> R {
        debug_assert!(
            uses.iter().enumerate().all(|(i, u)| uses[..i].iter().all(|v| v.key != u.key)),
            "pass \"{label}\" names a resource twice"
        );
        let device = &self.device;
        labelled(device, cmd, label, || {
            let (mut images, mut buffers, mut memory) = (Vec::new(), Vec::new(), Vec::new());
            for usage in uses {
                let Some(Dependency { from, to, layouts }) = self.states.entry(usage.key).or_default().apply(usage)
                else {
                    continue;
                };
                let (src_stage, dst_stage) = (recorded(device, from.stage), recorded(device, to.stage));
                match usage.key {
                    Key::Image(raw) => {
                        // Without a transition the barrier keeps the image in the layout it is in.
                        let (old, new) = layouts.unwrap_or((usage.layout, usage.layout));
                        images.push(
                            vk::ImageMemoryBarrier2::default()
                                .image(raw)
                                .subresource_range(usage.range.expect("an image use has its range"))
                                .old_layout(old)
                                .new_layout(new)
                                .src_stage_mask(src_stage)
                                .src_access_mask(from.access)
                                .dst_stage_mask(dst_stage)
                                .dst_access_mask(to.access)
                                .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                                .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED),
                        )
                    }
                    Key::Buffer(raw) => buffers.push(
                        vk::BufferMemoryBarrier2::default()
                            .buffer(raw)
                            .offset(0)
                            .size(vk::WHOLE_SIZE)
                            .src_stage_mask(src_stage)
                            .src_access_mask(from.access)
                            .dst_stage_mask(dst_stage)
                            .dst_access_mask(to.access)
                            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED),
                    ),
                    Key::Memory(_) => memory.push(
                        vk::MemoryBarrier2::default()
                            .src_stage_mask(src_stage)
                            .src_access_mask(from.access)
                            .dst_stage_mask(dst_stage)
                            .dst_access_mask(to.access),
                    ),
                }
            }
            if !(images.is_empty() && buffers.is_empty() && memory.is_empty()) {
                let dependency = vk::DependencyInfo::default()
                    .image_memory_barriers(&images)
                    .buffer_memory_barriers(&buffers)
                    .memory_barriers(&memory);
                unsafe { device.raw.cmd_pipeline_barrier2(cmd, &dependency) };
            }
            record()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const COLOR: vk::ImageLayout = vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL;
    const SAMPLED: vk::ImageLayout = vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;

    fn image_use(kind: Kind, layout: vk::ImageLayout, access: Access) -> Use {
        let range = vk::ImageSubresourceRange::default().aspect_mask(vk::ImageAspectFlags::COLOR);
        Use { key: Key::Image(vk::Image::null()), range: Some(range), kind, layout, access }
    }

    fn buffer_use(kind: Kind, access: Access) -> Use {
        Use { key: Key::Buffer(vk::Buffer::null()), range: None, kind, layout: vk::ImageLayout::UNDEFINED, access }
    }

    #[test]
    fn an_attachment_drawn_then_sampled_then_drawn_again_gets_each_transition() {
        let mut state = State::default();
        let draw = image_use(Kind::Overwrite, COLOR, Access::COLOR_ATTACHMENT_WRITE);
        let sample = image_use(Kind::Read, SAMPLED, Access::SHADER_SAMPLED_READ);
        let first = state.apply(&draw).expect("the first draw moves the image out of UNDEFINED");
        assert_eq!((first.from, first.layouts), (Access::NONE, Some((vk::ImageLayout::UNDEFINED, COLOR))));
        let read = state.apply(&sample).expect("sampling needs the attachment in a read layout");
        assert_eq!(
            (read.from, read.to, read.layouts),
            (Access::COLOR_ATTACHMENT_WRITE, sample.access, Some((COLOR, SAMPLED)))
        );
        assert!(state.apply(&sample).is_none(), "a second read of what the first read saw needs nothing");
        let again = state.apply(&draw).expect("drawing over it waits for the reads");
        assert_eq!(again.layouts, Some((vk::ImageLayout::UNDEFINED, COLOR)), "old contents discarded");
        assert!(covers(again.from, Access { stage: sample.access.stage, access: vk::AccessFlags2::NONE }));
    }

    #[test]
    fn read_modify_writes_wait_for_each_other_and_reads_wait_once() {
        let mut state = State::default();
        let accumulate = buffer_use(Kind::Write, Access::COMPUTE_READ_WRITE);
        assert!(state.apply(&accumulate).is_none(), "a buffer's first use waits for nothing");
        let second = state.apply(&accumulate).expect("write after write");
        assert_eq!((second.from, second.to), (Access::COMPUTE_READ_WRITE, Access::COMPUTE_READ_WRITE));
        let host = buffer_use(Kind::Read, Access::HOST_READ);
        assert_eq!(state.apply(&host).map(|d| d.from), Some(Access::COMPUTE_READ_WRITE));
        assert!(state.apply(&host).is_none());
        let resolve = buffer_use(Kind::Read, Access::COMPUTE_READ);
        assert!(state.apply(&resolve).is_some(), "the host's visibility is not the compute stage's");
        let next = state.apply(&accumulate).expect("write after read");
        assert!(covers(next.from, Access::HOST_READ) && covers(next.from, Access::COMPUTE_READ_WRITE));
    }
}
