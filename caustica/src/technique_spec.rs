//! Technique specs: a registry name with setting overrides, as `caustica report` and the
//! references take them (`adaptive-caustics:deposit=screen+metric=level`).

use caustica_core::techniques::technique_names;

/// A technique spec `name[:key=value[+key=value...]]` as (registry name, settings set over
/// the plan's): a value that parses as JSON is taken as such (`64`, `true`), any other
/// as a string (`screen`). Errors name the spec and the registry's techniques.
pub fn technique_spec(
    spec: &str,
) -> Result<(&str, serde_json::Map<String, serde_json::Value>), String> {
    let (name, rest) = spec.split_once(':').unwrap_or((spec, ""));
    if !technique_names().contains(&name) {
        return Err(format!(
            "unknown technique '{name}' in '{spec}'; available: {}",
            technique_names().join(", ")
        ));
    }
    let mut settings = serde_json::Map::new();
    for pair in rest.split('+').filter(|p| !p.is_empty()) {
        let (k, v) = pair
            .split_once('=')
            .ok_or_else(|| format!("technique '{spec}': '{pair}' is not key=value"))?;
        let value = serde_json::from_str(v).unwrap_or_else(|_| serde_json::Value::from(v));
        // `block.field` sets a field of a block (`frame.seed=3`); a bare field name is
        // found in its block by the technique (`seed=3`)
        match k.split_once('.') {
            Some((block, field)) => {
                let b = settings
                    .entry(block.to_string())
                    .or_insert_with(|| serde_json::Value::Object(Default::default()));
                match b.as_object_mut() {
                    Some(b) => {
                        b.insert(field.to_string(), value);
                    }
                    None => return Err(format!("technique '{spec}': '{block}' is not a block")),
                }
            }
            None => {
                settings.insert(k.to_string(), value);
            }
        }
    }
    Ok((name, settings))
}
