// specialize.wgsl — settings as pipeline-overridable constants. SPEC_X = INVALID (the default) reads the
// setting from the uniform at run time (the viewer's generic pipeline); any other value fixes it at
// pipeline creation, so the branches of every other choice fold away (headless renders, benchmarks).

override SPEC_MODE: u32 = 0xffffffffu;
override SPEC_STRATEGY: u32 = 0xffffffffu;
override SPEC_LIGHT_SAMPLING: u32 = 0xffffffffu;
override SPEC_ENV_SAMPLING: u32 = 0xffffffffu;
override SPEC_LIGHT_SELECT: u32 = 0xffffffffu;
override SPEC_HEURISTIC: u32 = 0xffffffffu;
override SPEC_MIS_KIND: u32 = 0xffffffffu;
override SPEC_SAMPLER: u32 = 0xffffffffu;
/// 1 when a shading point takes at most one direction sample (`--bsdf-samples` ≤ 1), fixed at pipeline creation.
override SPEC_ONE_DIRECTION: u32 = 0xffffffffu;

fn cfg_mode() -> u32 { return select(params.mode, SPEC_MODE, SPEC_MODE != INVALID); }
fn cfg_strategy() -> u32 { return select(params.strategy, SPEC_STRATEGY, SPEC_STRATEGY != INVALID); }
fn cfg_light_sampling() -> u32 { return select(params.light_sampling, SPEC_LIGHT_SAMPLING, SPEC_LIGHT_SAMPLING != INVALID); }
fn cfg_env_sampling() -> u32 { return select(params.env_sampling, SPEC_ENV_SAMPLING, SPEC_ENV_SAMPLING != INVALID); }
fn cfg_light_select() -> u32 { return select(params.light_select, SPEC_LIGHT_SELECT, SPEC_LIGHT_SELECT != INVALID); }
fn cfg_heuristic() -> u32 { return select(params.heuristic, SPEC_HEURISTIC, SPEC_HEURISTIC != INVALID); }
fn cfg_mis_kind() -> u32 { return select(params.mis_kind, SPEC_MIS_KIND, SPEC_MIS_KIND != INVALID); }
fn cfg_filter() -> u32 { return params.pixel_filter; }
fn cfg_sampler() -> u32 { return select(params.sampler, SPEC_SAMPLER, SPEC_SAMPLER != INVALID); }
