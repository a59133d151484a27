//! `htngtp facts`: the shared literals a scene makes true (the paper's Fig. 5).

use std::path::PathBuf;

use geometry::effort::MAX_EFFORT;
use geometry::facts::{FactParams, effort_table, relations};
use geometry::mightability::{Mightability, MightabilityParams};
use serde::Serialize;

/// Arguments of `htngtp facts`.
#[derive(clap::Args)]
#[command(
    about = "Print the shared literals a scene makes true (visible, reachable, on, inside, covered-by)",
    long_about = "Compute the shared literals of a scene (docs/scene-format.md) from its geometry, as \
                  the paper's Fig. 5: for every agent and movable object, the least effort level \
                  at which the agent sees it (pixel visibility >= the threshold) and reaches it, \
                  then on / inside / covered-by among objects.\n\n\
                  Effort levels: 0 already in view / in the hand; 1 turn the head / extend the \
                  arm; 2 turn the torso or lean (robot: turn around); 3 stand up (robot: raise or \
                  lower the torso); 4 walk / drive. `--json` prints a list of \
                  {predicate, args, effort}."
)]
pub struct Args {
    /// The scene file (TOML).
    pub scene: PathBuf,
    /// Read the scene even when objects start inside one another (a warning then, not an
    /// error); a robot inside furniture is still refused.
    #[arg(long)]
    pub allow_initial_contact: bool,
    /// Print JSON: a list of {predicate, args, effort}.
    #[arg(long)]
    pub json: bool,
    /// Fraction of an object's pixels an agent must see for `visible` (0 < t <= 1).
    #[arg(long, default_value_t = 0.5)]
    pub threshold: f32,
    /// Pixel grid (N x N) of each visibility query.
    #[arg(long, default_value_t = 64)]
    pub resolution: usize,
    /// Also compute the mightability maps (5 cm grids per agent and effort level) and print how
    /// many cells each agent sees and reaches per level, with the time taken.
    #[arg(long)]
    pub maps: bool,
}

#[derive(Serialize)]
struct JsonFact {
    predicate: String,
    args: Vec<String>,
    effort: Option<u8>,
}

fn level(e: Option<u8>) -> String {
    match e {
        Some(e) => format!("E={e}"),
        None => "E=- (not possible)".to_string(),
    }
}

pub fn run(args: Args) -> anyhow::Result<u8> {
    if !(args.threshold > 0.0 && args.threshold <= 1.0) {
        eprintln!(
            "error: --threshold must be in (0, 1], got {}",
            args.threshold
        );
        return Ok(crate::exit::BAD_INPUT);
    }
    if !(1..=1024).contains(&args.resolution) {
        eprintln!("error: --resolution must be between 1 and 1024");
        return Ok(crate::exit::BAD_INPUT);
    }
    let world = match crate::cmd::geo::load_world(&args.scene, args.allow_initial_contact) {
        Ok(w) => w,
        Err(e) => {
            eprintln!("error: {}", htn::text::clip(&e.to_string()));
            return Ok(crate::exit::BAD_INPUT);
        }
    };
    let params = FactParams {
        vis_threshold: args.threshold,
        resolution: args.resolution,
        ..FactParams::default()
    };
    let table = effort_table(&world, None, &params);
    let rel = relations(&world, &params);
    if args.json {
        let mut out = Vec::new();
        for t in &table {
            for (o, vis, reach) in &t.objects {
                for (pred, e) in [("visible", vis), ("reachable", reach)] {
                    if e.is_some() {
                        out.push(JsonFact {
                            predicate: pred.into(),
                            args: vec![o.clone(), t.agent.clone()],
                            effort: *e,
                        });
                    }
                }
            }
        }
        for f in rel {
            out.push(JsonFact {
                predicate: f.predicate,
                args: f.args,
                effort: None,
            });
        }
        println!("{}", serde_json::to_string_pretty(&out)?);
        return Ok(crate::exit::OK);
    }
    let scene = world.scene();
    println!(
        "Scene `{}` ({}): {} agents, {} objects; visible = at least {:.0}% of the object's pixels \
         ({}x{} rays)",
        scene.name,
        args.scene.display(),
        world.agent_count(),
        world.object_count(),
        100.0 * args.threshold,
        args.resolution,
        args.resolution
    );
    for t in &table {
        println!();
        println!("For {} ({}):", t.agent.to_uppercase(), t.kind);
        for (o, vis, reach) in &t.objects {
            println!(
                "  {o} is Vis with {}, Reach with {}",
                level(*vis),
                level(*reach)
            );
        }
    }
    println!();
    println!(
        "Effort levels: 0 in view / in hand, 1 turn head / extend arm, 2 torso turn or lean \
         (robot: turn around), 3 stand up (robot: torso lift), 4 walk / drive."
    );
    if args.maps {
        let start = std::time::Instant::now();
        let m = Mightability::compute(&world, &MightabilityParams::default());
        let took = start.elapsed();
        println!();
        println!(
            "Mightability maps: {} x {} x {} cells of {} m, computed in {:.2} s",
            m.grid.dims[0],
            m.grid.dims[1],
            m.grid.dims[2],
            m.grid.cell,
            took.as_secs_f64()
        );
        for a in world.agent_ids() {
            let name = world.agent(a).name().to_uppercase();
            let row = |vis: bool| {
                (0..=MAX_EFFORT)
                    .map(|l| format!("E<={l}: {}", m.count(a, l, vis)))
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            println!("  {name} sees    {}", row(true));
            println!("  {name} reaches {}", row(false));
        }
    }
    println!();
    println!("Relations:");
    if rel.is_empty() {
        println!("  (none)");
    }
    for f in rel {
        println!("  {}({})", f.predicate, f.args.join(", "));
    }
    Ok(crate::exit::OK)
}
