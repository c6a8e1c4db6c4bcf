//! The thermal network: `[[node]]`, `[[boundary]]`, `[[conductor]]`,
//! `[[radiation]]`, `[[mode]]`, `[[heater]]`, and the table of node names.

use super::*;
use crate::spec::registry as r;

/// The names of a network's nodes, diffusion and boundary, as the spec's elements
/// refer to them.
pub(super) struct NodeTable {
    names: HashMap<String, NodeRef>,
}

impl NodeTable {
    /// The node `name` (at key `p`).
    pub(super) fn lookup(&self, cx: &Cx, p: &KeyPath, name: &str) -> Result<NodeRef, SpecError> {
        self.names.get(name).copied().ok_or_else(|| {
            let mut known: Vec<&str> = self.names.keys().map(String::as_str).collect();
            known.sort();
            cx.err(
                p,
                format!("unknown node `{name}` (known: {})", known.join(", ")),
            )
        })
    }

    /// The diffusion node `name` (at key `p`): a boundary is refused.
    pub(super) fn diffusion(&self, cx: &Cx, p: &KeyPath, name: &str) -> Result<usize, SpecError> {
        match self.lookup(cx, p, name)? {
            NodeRef::Diffusion(i) => Ok(i),
            NodeRef::Boundary(_) => Err(cx.err(
                p,
                format!("`{name}` is a boundary node; this needs a diffusion node"),
            )),
        }
    }

    /// The two ends of a link (`between` at element `p`): two different nodes, not
    /// both boundaries.
    pub(super) fn pair(
        &self,
        cx: &Cx,
        p: &KeyPath,
        between: &[String],
    ) -> Result<(NodeRef, NodeRef), SpecError> {
        let bp = p.key("between");
        if between.len() != 2 {
            return Err(cx.err(
                &bp,
                format!(
                    "lists {} node(s); a link joins exactly two: between = [\"a\", \"b\"]",
                    between.len()
                ),
            ));
        }
        let a = self.lookup(cx, &bp.at(0), &between[0])?;
        let b = self.lookup(cx, &bp.at(1), &between[1])?;
        if a == b {
            return Err(cx.err(&bp, format!("links `{}` to itself", between[0])));
        }
        if matches!((a, b), (NodeRef::Boundary(_), NodeRef::Boundary(_))) {
            return Err(cx.err(
                &bp,
                "links two boundary nodes; it would carry no heat the model tracks",
            ));
        }
        Ok((a, b))
    }
}

/// `[[node]]` and `[[boundary]]` (after the built-in `space` at `space_sink_k`), and
/// the table of their names.
pub(super) fn nodes_and_boundaries(
    cx: &Cx,
    keys: &ElementKeys,
    node_specs: Vec<NodeSpec>,
    boundary_specs: Vec<BoundarySpec>,
    space_sink_k: f64,
) -> Result<(NodeTable, Vec<DiffusionNode>, Vec<BoundaryNode>), SpecError> {
    let mut names: HashMap<String, NodeRef> = HashMap::new();
    let np = KeyPath::new("node");
    let mut nodes = Vec::new();
    for (i, n) in node_specs.into_iter().enumerate() {
        let p = np.elem(i, &keys.node[i]);
        check_name(cx, &np.at(i).key("name"), &n.name, &names)?;
        let node = DiffusionNode {
            capacitance_j_per_k: cx.read(&r::CAPACITANCE_J_PER_K, &p, n.capacitance_j_per_k)?,
            initial_temperature_k: cx.read(
                &r::INITIAL_TEMPERATURE_K,
                &p,
                n.initial_temperature_k,
            )?,
            radius_m: match n.radius_mm {
                Some(r) => Some(cx.read(&r::RADIUS_MM, &p, r)? * 1e-3),
                None => None,
            },
            name: n.name,
        };
        names.insert(node.name.clone(), NodeRef::Diffusion(i));
        nodes.push(node);
    }
    if nodes.is_empty() {
        return Err(cx.err(
            &np,
            "the network needs at least one diffusion node ([[node]])",
        ));
    }
    let bp = KeyPath::new("boundary");
    let mut boundaries = vec![BoundaryNode {
        name: SPACE.to_string(),
        temperature_k: Profile::Constant(space_sink_k),
    }];
    names.insert(SPACE.to_string(), NodeRef::Boundary(0));
    for (i, b) in boundary_specs.into_iter().enumerate() {
        let p = bp.elem(i, &keys.boundary[i]);
        if b.name == SPACE {
            return Err(cx.err(
                &bp.at(i).key("name"),
                "`space` is built in; set its temperature with environment.space_sink_k",
            ));
        }
        check_name(cx, &bp.at(i).key("name"), &b.name, &names)?;
        let field = &r::BOUNDARY_TEMPERATURE_K;
        let t = cx.profile(&field.key(&p), b.temperature_k, &|pp, v| {
            cx.quantity(field.quantity, pp, v)
        })?;
        names.insert(b.name.clone(), NodeRef::Boundary(boundaries.len()));
        boundaries.push(BoundaryNode {
            name: b.name,
            temperature_k: t,
        });
    }
    Ok((NodeTable { names }, nodes, boundaries))
}

/// `[[conductor]]` and `[[radiation]]`.
pub(super) fn links(
    cx: &Cx,
    keys: &ElementKeys,
    table: &NodeTable,
    conductor_specs: &[ConductorSpec],
    radiation_specs: &[RadiationSpec],
) -> Result<(Vec<Conductor>, Vec<Radiator>), SpecError> {
    let mut conductors = Vec::new();
    for (i, c) in conductor_specs.iter().enumerate() {
        let p = KeyPath::new("conductor").elem(i, &keys.conductor[i]);
        let (a, b) = table.pair(cx, &p, &c.between)?;
        conductors.push(Conductor {
            a,
            b,
            conductance_w_per_k: cx.read(&r::CONDUCTANCE_W_PER_K, &p, c.conductance_w_per_k)?,
        });
    }
    let mut radiators = Vec::new();
    for (i, x) in radiation_specs.iter().enumerate() {
        let p = KeyPath::new("radiation").elem(i, &keys.radiation[i]);
        let (a, b) = table.pair(cx, &p, &x.between)?;
        let ea = cx.product(
            &p,
            (x.emissivity_area_m2, &r::EMISSIVITY_AREA_M2),
            (x.emissivity, &r::EMISSIVITY),
            x.area_m2,
        )?;
        radiators.push(Radiator {
            a,
            b,
            emissivity_area_m2: ea,
        });
    }

    Ok((conductors, radiators))
}

/// `[[mode]]`: named windows of mission time.
pub(super) fn modes(
    cx: &Cx,
    keys: &ElementKeys,
    specs: Vec<ModeSpec>,
) -> Result<Vec<Mode>, SpecError> {
    let mut modes = Vec::new();
    for (i, m) in specs.into_iter().enumerate() {
        let p = KeyPath::new("mode").elem(i, &keys.mode[i]);
        if Schedule::RESERVED.contains(&m.name.as_str()) {
            return Err(cx.err(
                &KeyPath::new("mode").at(i).key("name"),
                format!("`{}` cannot name a mode", m.name),
            ));
        }
        if modes.iter().any(|x: &Mode| x.name == m.name) {
            return Err(cx.err(
                &KeyPath::new("mode").at(i).key("name"),
                format!("mode `{}` is defined twice", m.name),
            ));
        }
        let (windows, wkey, scale) = match (m.windows_s, m.windows_days) {
            (Some(w), None) => (w, r::WINDOWS_S.name, 1.0),
            (None, Some(w)) => (w, r::WINDOWS_DAYS.name, SECONDS_PER_DAY),
            _ => {
                let (s, d) = (r::WINDOWS_S.name, r::WINDOWS_DAYS.name);
                return Err(cx.err(&p, format!("give exactly one of `{s}` or `{d}`")));
            }
        };
        let mut windows_s = Vec::new();
        let mut last_end = f64::NEG_INFINITY;
        for (k, w) in windows.into_iter().enumerate() {
            let wp = p.key(wkey).at(k);
            let [a, b] = w[..] else {
                return Err(cx.err(
                    &wp,
                    format!("a window is [start, end] (got {} numbers)", w.len()),
                ));
            };
            cx.finite(&wp, a)?;
            cx.finite(&wp, b)?;
            if b <= a || a < last_end {
                return Err(cx.err(
                    &wp,
                    "windows are [start, end] with end > start, in increasing order, not overlapping",
                ));
            }
            last_end = b;
            windows_s.push((a * scale, b * scale));
        }
        modes.push(Mode {
            name: m.name,
            windows_s,
        });
    }

    Ok(modes)
}

/// `[[heater]]`: thermostat-controlled heaters.
pub(super) fn heaters(
    cx: &Cx,
    keys: &ElementKeys,
    table: &NodeTable,
    specs: Vec<HeaterSpec>,
) -> Result<Vec<Heater>, SpecError> {
    let diffusion = |p: &KeyPath, name: &str| table.diffusion(cx, p, name);
    let mut heaters = Vec::new();
    for (i, h) in specs.into_iter().enumerate() {
        let p = KeyPath::new("heater").elem(i, &keys.heater[i]);
        let node = diffusion(&p.key("node"), &h.node)?;
        let sensor_node = match &h.sensor_node {
            Some(s) => diffusion(&p.key("sensor_node"), s)?,
            None => node,
        };
        let on_k = cx.read(&r::ON_K, &p, h.on_k)?;
        let off_k = cx.read(&r::OFF_K, &p, h.off_k)?;
        check::heater_band(&r::OFF_K.key(&p), on_k, off_k)?;
        heaters.push(Heater {
            name: h.name.unwrap_or_else(|| format!("heater.{}", h.node)),
            node,
            sensor_node,
            power_w: cx.read(&r::HEATER_POWER_W, &p, h.power_w)?,
            on_k,
            off_k,
        });
    }

    Ok(heaters)
}
