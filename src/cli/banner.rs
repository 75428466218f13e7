//! The node's start-up banner: its name, domain, scene, pacing, and every topic and
//! service it reads and writes, one line each (the caller prints them on stderr).

use crate::ros::node::{run_outputs, Lockstep, NodeConfig, Pacing};
use crate::session::OutputTable;

/// The banner's lines, prefixed `[developable_sim]`.
pub fn banner(config: &NodeConfig) -> Vec<String> {
    let (scene, names) = (&config.scene, &config.names);
    let mode = match (&config.lockstep, config.pacing) {
        (Lockstep::Service, _) => "lock-step on ~/step".to_string(),
        (Lockstep::Handle(h), _) => format!("lock-step on {}", names.handles[*h]),
        (Lockstep::Off, Pacing::AsFastAsPossible) => "as fast as possible".into(),
        (Lockstep::Off, Pacing::RealTime { factor }) => {
            format!("real time x{factor} (dt {} s)", scene.world.dt())
        }
    };
    let mut lines = vec![format!(
        "[developable_sim] node {} on ROS domain {}: scene {} ({}), {mode}",
        names.fqn(),
        config.domain_id,
        scene.name,
        scene.file.display()
    )];
    for (h, t) in scene.world.handles().iter().zip(&names.handles) {
        lines.push(format!(
            "[developable_sim]   in : {t} (geometry_msgs/msg/PoseStamped, frame `{}`) -> handle {}",
            scene.frame_id, h.name
        ));
    }
    // the outputs table as the node builds it (`SimNode::new`)
    let run = run_outputs(config);
    if let Ok(table) = OutputTable::for_scene(scene, names, run) {
        for row in table.rows.iter().filter(|r| r.want.published) {
            lines.push(format!(
                "[developable_sim]   out: {} ({})",
                row.topic,
                row.type_name()
            ));
        }
    }
    lines.push(format!(
        "[developable_sim]   services: {} {} (std_srvs/srv/Trigger), {} (std_srvs/srv/SetBool)",
        names.reset, names.step, names.set_paused
    ));
    lines.push(format!(
        "[developable_sim]   services: {} (developable_sim/srv/Grasp), {} \
         (developable_sim/srv/Release)",
        names.grasp, names.release
    ));
    let sim = &names.simulation;
    lines.push(format!(
        "[developable_sim]   services: {} {} {} {} {}, action: {} (simulation_interfaces 1.5.1)",
        sim.get_features, sim.reset, sim.step, sim.get_state, sim.set_state, sim.simulate_steps
    ));
    if !names.handle_grasp.is_empty() {
        lines.push(format!(
            "[developable_sim]   services: {} (std_srvs/srv/SetBool: true closes, false opens)",
            names.handle_grasp.join(" ")
        ));
    }
    if let Some((r, _)) = &config.record {
        lines.push(format!(
            "[developable_sim]   recording into {}",
            r.display()
        ));
    }
    lines
}
