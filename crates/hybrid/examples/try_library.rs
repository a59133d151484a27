fn main() {
    let args: Vec<String> = std::env::args().collect();
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../domains/library");
    let problem = args.get(1).map(String::as_str).unwrap_or("lend-and-debit");
    let scene = args.get(2).map(String::as_str).unwrap_or("scene.toml");
    let domain = args.get(3).map(String::as_str).unwrap_or("domain.hddl");
    let t = std::time::Instant::now();
    let run = hybrid::plan_files(
        &dir.join(domain),
        &dir.join(format!("{problem}.hddl")),
        &dir.join(scene),
        &Default::default(),
    );
    match run {
        Err(e) => println!("error: {e}"),
        Ok(run) => {
            println!("{:?}", t.elapsed());
            match &run.result.outcome {
                htn::planner::Outcome::Found { plan } => {
                    for a in &plan.actions {
                        println!(
                            "{} {:?} {}",
                            a.name,
                            a.args,
                            a.geometric
                                .as_ref()
                                .map(|g| format!("+{:?} -{:?}", g.add, g.delete))
                                .unwrap_or_default()
                        );
                    }
                }
                o => println!("{o:?}"),
            }
            println!(
                "{}",
                serde_json::to_string_pretty(&run.result.stats).unwrap()
            );
        }
    }
}
