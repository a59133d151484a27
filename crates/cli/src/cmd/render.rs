//! `htngtp render`: draw a scene as a PNG picture, from an agent's eyes or from above.

use std::path::PathBuf;

use anyhow::Context;
use geometry::effort::aim_head;
use geometry::render::{Camera, agent_camera, render_eye_view, render_visual};
use geometry::scene::AgentKind;

/// Arguments of `htngtp render`.
#[derive(clap::Args)]
#[command(
    about = "Draw a scene as a PNG picture, from an agent's eyes or from above",
    long_about = "Draw a scene (docs/scene-format.md) with the CPU ray caster: shaded, every object in \
                  its own colour, outlines between objects, a checkered floor. Agents are drawn \
                  in the scene's posture, each link by its URDF visual meshes (STL, COLLADA, \
                  OBJ; in the material's colour when the URDF gives one) when it has any, by \
                  its collision shapes otherwise.\n\n\
                  Views: `human` (the first human's eyes), `robot` (the first robot's head camera), \
                  `top` (orthographic, from above), or an agent's name (e.g. `member`, `pr2`). \
                  An agent's view uses its field of view (people 120 x 90 degrees, the robot's \
                  camera 70 x 52.5 unless the scene says otherwise) and its current head pose."
)]
pub struct Args {
    /// The scene file (TOML).
    pub scene: PathBuf,
    /// Read the scene even when objects start inside one another (a warning then, not an
    /// error); a robot inside furniture is still refused.
    #[arg(long)]
    pub allow_initial_contact: bool,
    /// human | robot | top | AGENT-NAME
    #[arg(long, default_value = "top")]
    pub view: String,
    /// Where to write the PNG.
    #[arg(long)]
    pub out: PathBuf,
    /// Image width in pixels.
    #[arg(long, default_value_t = 800)]
    pub width: usize,
    /// Image height in pixels (default: from the view's aspect ratio).
    #[arg(long)]
    pub height: Option<usize>,
    /// With an agent's view: turn its head towards this object first (within the joint
    /// limits), as the visibility test at effort level 1 does.
    #[arg(long, value_name = "OBJECT")]
    pub look_at: Option<String>,
}

pub fn run(args: Args) -> anyhow::Result<u8> {
    let world = match crate::cmd::geo::load_world(&args.scene, args.allow_initial_contact) {
        Ok(w) => w,
        Err(e) => {
            eprintln!("error: {}", htn::text::clip(&e.to_string()));
            return Ok(crate::exit::BAD_INPUT);
        }
    };
    if args.width == 0 || args.width > 4096 || args.height.is_some_and(|h| h == 0 || h > 4096) {
        eprintln!("error: --width and --height must be between 1 and 4096");
        return Ok(crate::exit::BAD_INPUT);
    }
    let by_kind = |kind: AgentKind| world.agent_ids().find(|&a| world.agent(a).kind() == kind);
    let agent = match args.view.as_str() {
        "top" => None,
        "human" => Some(by_kind(AgentKind::Human).context("the scene has no human agent")?),
        "robot" => Some(by_kind(AgentKind::Robot).context("the scene has no robot agent")?),
        name => Some(world.agent_id(name).with_context(|| {
            let names: Vec<&str> = world.agent_ids().map(|a| world.agent(a).name()).collect();
            format!(
                "unknown view `{name}`: expected human, robot, top or an agent name ({})",
                names.join(", ")
            )
        })?),
    };
    let mut world = world;
    if let Some(name) = &args.look_at {
        let Some(a) = agent else {
            anyhow::bail!("--look-at needs an agent's view (human, robot or a name), not `top`");
        };
        let o = world
            .object_id(name)
            .with_context(|| format!("--look-at: no object `{name}` in the scene"))?;
        let st = world.agent_state(a).clone();
        let mut q = st.q.clone();
        aim_head(&world, a, st.base, &mut q, world.object_aabb(o).center());
        world.set_agent_config(a, st.base, &q);
    }
    let (camera, height) = match agent {
        Some(a) => {
            let cam = agent_camera(&world, a);
            let fov = world.agent(a).fov;
            let aspect = (0.5 * fov[0]).tan() / (0.5 * fov[1]).tan();
            let h = args
                .height
                .unwrap_or(((args.width as f32 / aspect).round() as usize).max(1));
            (cam, h)
        }
        None => {
            let b = world.bounds();
            let h = args.height.unwrap_or(args.width);
            (Camera::top(&b, args.width as f32 / h as f32), h)
        }
    };
    let (img, warnings) = match agent {
        Some(a) => render_eye_view(&world, a, args.width, height),
        None => render_visual(&world, &camera, args.width, height),
    };
    for w in warnings {
        eprintln!("warning: {w}");
    }
    img.save_png(&args.out).map_err(anyhow::Error::msg)?;
    eprintln!(
        "wrote {} ({} x {}, view {})",
        args.out.display(),
        args.width,
        height,
        args.view
    );
    Ok(crate::exit::OK)
}
