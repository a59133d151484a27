//! `htngtp export`: a plan JSON's timed joint trajectories in other formats. The one format so
//! far, `joint-trajectory-yaml`, writes one YAML file per trajectory in the field layout of ROS's
//! `trajectory_msgs/JointTrajectory` message.

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::Context;
use serde_json::Value;

use crate::exit;

/// Output formats of `htngtp export`.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum Format {
    /// One YAML file per trajectory, laid out as ROS's `trajectory_msgs/JointTrajectory`.
    JointTrajectoryYaml,
}

/// Arguments of `htngtp export`.
#[derive(clap::Args)]
#[command(
    after_help = "Reads the `joint_trajectory` of every GS trajectory of a plan JSON \
    (`htngtp plan --json-out`, `htngtp demo`; see docs/plan-json.md) and writes, for \
    `--format joint-trajectory-yaml`, one file per trajectory into DIR (created if absent), \
    named `step-SSS-traj-K-AGENT-GROUP.yaml`. Each file has the fields of ROS's \
    trajectory_msgs/JointTrajectory: header (stamp 0, frame_id `world` for base drives, else the \
    agent's root link), joint_names, and points with positions, velocities, accelerations and \
    effort (both empty) and time_from_start {sec, nanosec}; a comment line names the step, \
    action and trajectory. Base drives have the joints base_x, base_y, base_yaw. A trajectory \
    that moves a gripper (`gripper_joint`) also gets `step-SSS-traj-K-AGENT-GROUP-gripper.yaml`: \
    that joint alone at each point's `gripper_position`, at the same times, for a gripper's \
    trajectory controller. Numbers are written so that they read back exactly.\n\nExit codes: 0 written, 3 bad input (unreadable \
    or malformed plan JSON, a plan with no joint trajectories, a failed write)."
)]
pub struct Args {
    /// The plan JSON.
    pub plan: PathBuf,
    /// What to write.
    #[arg(long, value_enum)]
    pub format: Format,
    /// The directory to write into (created if absent; existing files of the same name are
    /// replaced).
    pub dir: PathBuf,
}

pub fn run(args: Args) -> anyhow::Result<u8> {
    crate::input::check_file(&args.plan)?;
    let text = std::fs::read_to_string(&args.plan)
        .with_context(|| format!("cannot read {}", args.plan.display()))?;
    let plan: Value = serde_json::from_str(&text)
        .with_context(|| format!("{}: not valid JSON", args.plan.display()))?;
    let files = match args.format {
        Format::JointTrajectoryYaml => {
            yaml_files(&plan).map_err(|e| anyhow::anyhow!("{}: {e}", args.plan.display()))?
        }
    };
    if files.is_empty() {
        anyhow::bail!(
            "{}: no trajectory has a `joint_trajectory` (a plan without geometric steps, or \
             written before timed trajectories; plan it again)",
            args.plan.display()
        );
    }
    std::fs::create_dir_all(&args.dir)
        .with_context(|| format!("cannot create {}", args.dir.display()))?;
    for (name, body) in &files {
        let path = args.dir.join(name);
        std::fs::write(&path, body).with_context(|| format!("cannot write {}", path.display()))?;
    }
    println!(
        "wrote {} joint trajectories to {}",
        files.len(),
        args.dir.display()
    );
    Ok(exit::OK)
}

/// The file name and YAML text of every joint trajectory of `plan`, in step order.
fn yaml_files(plan: &Value) -> Result<Vec<(String, String)>, String> {
    let roots = root_links(plan);
    let mut out = Vec::new();
    let Some(steps) = plan.get("steps").and_then(Value::as_array) else {
        return Err("no `steps` array".into());
    };
    for (i, step) in steps.iter().enumerate() {
        let trajs = step
            .get("gtp")
            .and_then(|g| g.get("trajectories"))
            .and_then(Value::as_array);
        let action = step.get("action").and_then(Value::as_str).unwrap_or("");
        for (k, t) in trajs.into_iter().flatten().enumerate() {
            let Some(jt) = t.get("joint_trajectory").filter(|v| !v.is_null()) else {
                continue;
            };
            let path = format!("steps[{i}].gtp.trajectories[{k}].joint_trajectory");
            let agent = jt.get("agent").and_then(Value::as_str).unwrap_or("");
            let group = jt.get("group").and_then(Value::as_str).unwrap_or("");
            let label = t.get("label").and_then(Value::as_str).unwrap_or("");
            let frame = if group == "base" {
                "world"
            } else {
                roots
                    .iter()
                    .find(|(a, _)| a == agent)
                    .map_or("", |(_, r)| r)
            };
            let comment = format!(
                "step {i} ({}), trajectory {k} ({}): agent {}, group {}",
                one_line(action),
                one_line(label),
                one_line(agent),
                one_line(group)
            );
            let body = yaml(jt, frame, &comment).map_err(|e| format!("`{path}`: {e}"))?;
            let name = format!(
                "step-{i:03}-traj-{k}-{}-{}",
                file_part(agent),
                file_part(group)
            );
            out.push((format!("{name}.yaml"), body));
            if let Some(g) = gripper_trajectory(jt) {
                let comment = format!("{comment}: its gripper");
                let body = yaml(&g, frame, &comment).map_err(|e| format!("`{path}`: {e}"))?;
                out.push((format!("{name}-gripper.yaml"), body));
            }
        }
    }
    Ok(out)
}

/// The gripper's part of joint trajectory `jt` as a joint trajectory of its own, for a
/// gripper's controller: its `gripper_joint` at each point's `gripper_position`, at the same
/// times, velocities by central differences (at rest at both ends); `None` where `jt` declares
/// no gripper or a point lacks its position.
fn gripper_trajectory(jt: &Value) -> Option<Value> {
    let joint = jt.get("gripper_joint")?.as_str()?;
    let points = jt.get("points")?.as_array()?;
    let at: Vec<(f64, f64)> = points
        .iter()
        .map(|p| {
            Some((
                p.get("time_from_start")?.as_f64()?,
                p.get("gripper_position")?.as_f64()?,
            ))
        })
        .collect::<Option<_>>()?;
    let velocity = |i: usize| {
        if i == 0 || i + 1 >= at.len() || at[i + 1].0 <= at[i - 1].0 {
            return 0.0;
        }
        (at[i + 1].1 - at[i - 1].1) / (at[i + 1].0 - at[i - 1].0)
    };
    let points: Vec<Value> = (0..at.len())
        .map(|i| {
            serde_json::json!({
                "positions": [at[i].1],
                "velocities": [velocity(i)],
                "time_from_start": at[i].0,
            })
        })
        .collect();
    Some(serde_json::json!({ "joint_names": [joint], "points": points }))
}

/// Each agent's root link (its first link in the scene), the frame its arm joints move in.
fn root_links(plan: &Value) -> Vec<(String, String)> {
    let agents = plan
        .get("scene")
        .and_then(|s| s.get("agents"))
        .and_then(Value::as_array);
    agents
        .into_iter()
        .flatten()
        .filter_map(|a| {
            let name = a.get("name")?.as_str()?;
            let root = a.get("links")?.get(0)?.get("name")?.as_str()?;
            Some((name.to_string(), root.to_string()))
        })
        .collect()
}

/// `s` as a file-name part: letters, digits, `-` and `_` kept, anything else `_`, at most 64.
fn file_part(s: &str) -> String {
    let p: String = s
        .chars()
        .take(64)
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if p.is_empty() { "_".into() } else { p }
}

/// `s` on one line, for a comment.
fn one_line(s: &str) -> String {
    s.chars()
        .take(200)
        .map(|c| if c.is_control() { ' ' } else { c })
        .collect()
}

/// A YAML double-quoted scalar (a JSON string is one).
fn quoted(s: &str) -> String {
    serde_json::to_string(s).unwrap_or_else(|_| "\"\"".into())
}

/// A list of finite numbers, with the length `len`.
fn numbers(v: Option<&Value>, what: &str, len: usize) -> Result<Vec<f64>, String> {
    let items = v
        .and_then(Value::as_array)
        .ok_or_else(|| format!("`{what}` is not an array"))?;
    if items.len() != len {
        return Err(format!(
            "`{what}` has {} values for {len} joints",
            items.len()
        ));
    }
    items
        .iter()
        .map(|x| {
            x.as_f64()
                .filter(|x| x.is_finite())
                .ok_or_else(|| format!("`{what}` has a value that is not a finite number"))
        })
        .collect()
}

/// A flow sequence of numbers, each written in the shortest form that reads back exactly, with
/// a decimal point and no exponent (so that YAML 1.1 readers such as PyYAML, which ROS 2's tools
/// use, read every one as a float).
fn flow(xs: &[f64]) -> String {
    let parts: Vec<String> = xs
        .iter()
        .map(|x| {
            let s = format!("{x}");
            if s.contains('.') { s } else { format!("{s}.0") }
        })
        .collect();
    format!("[{}]", parts.join(", "))
}

/// `t` seconds as ROS's `builtin_interfaces/Duration` (whole seconds, nanoseconds below 1e9).
pub fn duration(t: f64) -> (i64, u32) {
    let mut sec = t.floor();
    let mut nanosec = ((t - sec) * 1e9).round();
    if nanosec >= 1e9 {
        sec += 1.0;
        nanosec -= 1e9;
    }
    (sec as i64, nanosec as u32)
}

/// The YAML of one joint trajectory.
fn yaml(jt: &Value, frame: &str, comment: &str) -> Result<String, String> {
    let names: Vec<&str> = jt
        .get("joint_names")
        .and_then(Value::as_array)
        .ok_or("`joint_names` is not an array")?
        .iter()
        .map(|n| n.as_str().ok_or("a joint name is not a string"))
        .collect::<Result<_, _>>()?;
    let points = jt
        .get("points")
        .and_then(Value::as_array)
        .ok_or("`points` is not an array")?;
    let mut y = String::new();
    let _ = writeln!(y, "# {comment}");
    let _ = writeln!(
        y,
        "# trajectory_msgs/JointTrajectory, written by htngtp export"
    );
    let _ = writeln!(y, "header:");
    let _ = writeln!(y, "  stamp:");
    let _ = writeln!(y, "    sec: 0");
    let _ = writeln!(y, "    nanosec: 0");
    let _ = writeln!(y, "  frame_id: {}", quoted(frame));
    if names.is_empty() {
        let _ = writeln!(y, "joint_names: []");
    } else {
        let _ = writeln!(y, "joint_names:");
        for n in &names {
            let _ = writeln!(y, "  - {}", quoted(n));
        }
    }
    if points.is_empty() {
        let _ = writeln!(y, "points: []");
    } else {
        let _ = writeln!(y, "points:");
    }
    for (i, p) in points.iter().enumerate() {
        let positions = numbers(
            p.get("positions"),
            &format!("points[{i}].positions"),
            names.len(),
        )?;
        let velocities = numbers(
            p.get("velocities"),
            &format!("points[{i}].velocities"),
            names.len(),
        )?;
        let t = p
            .get("time_from_start")
            .and_then(Value::as_f64)
            .filter(|t| t.is_finite() && *t >= 0.0 && *t < 1e12)
            .ok_or_else(|| {
                format!("`points[{i}].time_from_start` is not a number of seconds in [0, 1e12)")
            })?;
        let (sec, nanosec) = duration(t);
        let _ = writeln!(y, "  - positions: {}", flow(&positions));
        let _ = writeln!(y, "    velocities: {}", flow(&velocities));
        let _ = writeln!(y, "    accelerations: []");
        let _ = writeln!(y, "    effort: []");
        let _ = writeln!(y, "    time_from_start:");
        let _ = writeln!(y, "      sec: {sec}");
        let _ = writeln!(y, "      nanosec: {nanosec}");
    }
    Ok(y)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_split_into_seconds_and_nanoseconds() {
        assert_eq!(duration(0.0), (0, 0));
        assert_eq!(duration(1.5), (1, 500_000_000));
        assert_eq!(duration(2.9999999999), (3, 0));
    }

    #[test]
    fn numbers_read_back_exactly() {
        for x in [0.1f64, 1.0 / 3.0, -2.5e-7, 1e-20, 123456.789, 0.0] {
            let s = flow(&[x]);
            let inner = &s[1..s.len() - 1];
            assert!(inner.contains('.') && !inner.contains('e'), "{inner}");
            let back: f64 = inner.parse().unwrap();
            assert_eq!(back, x);
        }
    }

    #[test]
    fn file_names_are_tame() {
        assert_eq!(file_part("pr2"), "pr2");
        assert_eq!(file_part("../a b"), "___a_b");
        assert_eq!(file_part(""), "_");
    }
}
