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
        if k.contains('.') {
            put_setting(&mut settings, k, value);
        } else {
            settings.insert(k.to_string(), value);
        }
    }
    Ok((name, settings))
}

/// A JSON object of technique settings, as the techniques read it.
pub type SettingsMap = serde_json::Map<String, serde_json::Value>;

/// Sets the settings field at `path` (`"frame.photons_w"`: a block's field; `"seed"`: a
/// top-level one) to `value`, over what `settings` held: the same field given in the
/// flat form of earlier versions (`"photons_w"` at the top level) is replaced too, so
/// that a settings file of either form takes a flag's value.
pub fn put_setting(settings: &mut SettingsMap, path: &str, value: serde_json::Value) {
    match path.split_once('.') {
        Some((block, field)) => {
            settings.remove(field);
            let b = settings
                .entry(block.to_string())
                .or_insert_with(|| serde_json::Value::Object(Default::default()));
            // a block given as something else stays as it was given: the technique's
            // settings reader rejects it, naming it
            if let Some(b) = b.as_object_mut() {
                b.insert(field.to_string(), value);
            }
        }
        None => {
            settings.insert(path.to_string(), value);
        }
    }
}

/// The settings field at `path` (`"frame.seed"`), given in its block or, in the flat form
/// of earlier versions, at the top level.
pub fn get_setting<'a>(settings: &'a SettingsMap, path: &str) -> Option<&'a serde_json::Value> {
    match path.split_once('.') {
        Some((block, field)) => settings
            .get(block)
            .and_then(|b| b.get(field))
            .or_else(|| settings.get(field)),
        None => settings.get(path),
    }
}

/// Lays `overrides` over `settings`: a block given in both merges field by field (a
/// spec's `frame.seed=3` keeps the settings file's other `frame` fields).
pub fn merge_settings(settings: &mut SettingsMap, overrides: SettingsMap) {
    for (k, v) in overrides {
        match (settings.get_mut(&k), v) {
            (Some(serde_json::Value::Object(b)), serde_json::Value::Object(o)) => {
                for (field, x) in o {
                    b.insert(field, x);
                }
            }
            (_, v) => {
                settings.insert(k, v);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_flag_replaces_a_field_given_in_either_form() {
        let mut s: SettingsMap =
            serde_json::from_str(r#"{"photons_w": 8, "frame": {"seed": 1}}"#).unwrap();
        put_setting(&mut s, "frame.photons_w", 64.into());
        assert_eq!(s.get("photons_w"), None);
        assert_eq!(get_setting(&s, "frame.photons_w"), Some(&64.into()));
        assert_eq!(get_setting(&s, "frame.seed"), Some(&1.into()));
        let (_, o) = technique_spec("sspm:frame.accumulate=true+point_emission=sphere").unwrap();
        merge_settings(&mut s, o);
        assert_eq!(get_setting(&s, "frame.seed"), Some(&1.into()));
        assert_eq!(get_setting(&s, "frame.accumulate"), Some(&true.into()));
        assert_eq!(s.get("point_emission"), Some(&"sphere".into()));
        // a block that is not an object is left for the technique to reject
        let mut s: SettingsMap = serde_json::from_str(r#"{"frame": 7}"#).unwrap();
        put_setting(&mut s, "frame.photons_w", 64.into());
        assert_eq!(s.get("frame"), Some(&7.into()));
    }
}
