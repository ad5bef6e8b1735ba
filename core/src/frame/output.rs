//! The one output vocabulary of every technique: the images a frame can give
//! ([`Output`]), the set a caller asks for ([`Outputs`]) and what a technique says of each
//! of its own ([`OutputInfo`]).
//!
//! A technique has a subset of the outputs (Sspm: composite, direct, raw and filtered
//! caustics; CausticMap and AdaptiveCaustics add the caustic atlas; PhotonGi: composite,
//! direct, raw and filtered indirect light) and lists it in
//! [`crate::frame::technique::Technique::outputs`]; asking one for an output it lacks is
//! [`crate::frame::error::Error::NoSuchOutput`]. The names ([`Output::stem`]) are the
//! file-name stems the CLI writes and the names its JSON uses.

use serde::{Deserialize, Serialize};

/// One output image of a frame. Camera-space outputs are linear radiance
/// (W/(sr m^2) per channel) of the camera's size, row-major from the top-left pixel; the
/// caustic atlas is irradiance (W/m^2) per atlas texel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub enum Output {
    /// Direct light plus the technique's caustics or indirect light.
    #[serde(rename = "composite")]
    Composite,
    /// Direct light alone (shadow rays, specular chains from mirror and glass pixels).
    #[serde(rename = "direct")]
    Direct,
    /// Caustic radiance, the technique's unfiltered estimate (Sspm's alpha: the mean hit
    /// distance).
    #[serde(rename = "caustics_raw")]
    RawCaustics,
    /// Caustic radiance after the technique's filter (Sspm's alpha: the density gather's
    /// radius in pixels where it gave light, or the bilateral gather's mean hit distance).
    #[serde(rename = "caustics_filtered")]
    FilteredCaustics,
    /// The gathered caustic map: irradiance (W/m^2) per texel of the receivers' atlas
    /// (`atlas_size` square; not camera-space).
    #[serde(rename = "caustic_atlas")]
    CausticAtlas,
    /// Indirect radiance, the technique's unfiltered estimate.
    #[serde(rename = "indirect_raw")]
    RawIndirect,
    /// Indirect radiance after the temporal blend and the A-Trous filter.
    #[serde(rename = "indirect")]
    FilteredIndirect,
}

impl Output {
    /// Every output, in the order techniques list theirs.
    pub const ALL: [Output; 7] = [
        Output::Composite,
        Output::Direct,
        Output::RawCaustics,
        Output::FilteredCaustics,
        Output::CausticAtlas,
        Output::RawIndirect,
        Output::FilteredIndirect,
    ];

    /// Name and file-name stem (`composite`, `direct`, `caustics_raw`,
    /// `caustics_filtered`, `caustic_atlas`, `indirect_raw`, `indirect`): the CLI's file
    /// names and the JSON form.
    pub const fn stem(self) -> &'static str {
        match self {
            Output::Composite => "composite",
            Output::Direct => "direct",
            Output::RawCaustics => "caustics_raw",
            Output::FilteredCaustics => "caustics_filtered",
            Output::CausticAtlas => "caustic_atlas",
            Output::RawIndirect => "indirect_raw",
            Output::FilteredIndirect => "indirect",
        }
    }

    /// The output whose [`Output::stem`] is `stem`.
    pub fn from_stem(stem: &str) -> Option<Output> {
        Output::ALL.into_iter().find(|o| o.stem() == stem)
    }

    /// What the image holds.
    pub const fn description(self) -> &'static str {
        match self {
            Output::Composite => "direct light + the technique's caustics or indirect light",
            Output::Direct => "direct light alone (shadow rays, specular chains)",
            Output::RawCaustics => "caustic radiance, unfiltered",
            Output::FilteredCaustics => "caustic radiance after the technique's filter",
            Output::CausticAtlas => "the gathered caustic map: irradiance (W/m^2) per atlas texel",
            Output::RawIndirect => "indirect radiance, unfiltered",
            Output::FilteredIndirect => "indirect radiance after the temporal and A-Trous filters",
        }
    }

    /// Whether the output is an image of the camera's size (radiance per pixel); false for
    /// the caustic atlas.
    pub const fn camera_space(self) -> bool {
        !matches!(self, Output::CausticAtlas)
    }

    const fn bit(self) -> u8 {
        1 << self as u8
    }
}

impl std::fmt::Display for Output {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.stem())
    }
}

/// A name that is no output's stem ([`Output::from_str`](std::str::FromStr)).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct UnknownOutput(pub String);

impl std::fmt::Display for UnknownOutput {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "no output '{}'; outputs: {}",
            self.0,
            stems(&Output::ALL)
        )
    }
}

impl std::error::Error for UnknownOutput {}

impl std::str::FromStr for Output {
    type Err = UnknownOutput;

    /// Parses an [`Output::stem`]; an unknown name is an error that lists the names.
    fn from_str(s: &str) -> Result<Output, Self::Err> {
        Output::from_stem(s).ok_or_else(|| UnknownOutput(s.to_string()))
    }
}

/// The outputs' stems, comma-separated (for messages).
pub fn stems(outputs: &[Output]) -> String {
    outputs
        .iter()
        .map(|o| o.stem())
        .collect::<Vec<_>>()
        .join(", ")
}

/// The set of outputs a caller asks a frame for (every one by default); passes and
/// buffers that no requested output needs are left out (see [`crate::frame::plan`]). A
/// technique reads only the outputs it has: [`Outputs::ALL`] asks each technique for all
/// of its own. Composite needs direct light and the filtered estimate internally even
/// when they are not asked for themselves.
///
/// JSON: `"all"` or a list of stems (`["composite", "caustics_filtered"]`). The object of
/// flags of earlier versions (`{"composite": true, "direct": false, ...}`, a missing flag
/// counting as requested; CausticMap's `atlas` flag is the caustic atlas) still loads.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct Outputs(u8);

impl Outputs {
    /// Every output.
    pub const ALL: Outputs = Outputs((1 << Output::ALL.len()) - 1);
    /// No output (not a valid request; a start for [`Outputs::with`]).
    pub const NONE: Outputs = Outputs(0);
    /// Only the filtered caustics (a renderer that does its own direct light).
    pub const CAUSTICS_ONLY: Outputs = Outputs(Output::FilteredCaustics.bit());
    /// Only the filtered indirect light (a renderer that does its own direct light).
    pub const INDIRECT_ONLY: Outputs = Outputs(Output::FilteredIndirect.bit());

    /// The set holding exactly `outputs`.
    pub const fn of(outputs: &[Output]) -> Outputs {
        let mut bits = 0;
        let mut i = 0;
        while i < outputs.len() {
            bits |= outputs[i].bit();
            i += 1;
        }
        Outputs(bits)
    }

    /// This set with `output` added.
    pub const fn with(self, output: Output) -> Outputs {
        Outputs(self.0 | output.bit())
    }

    /// This set with `output` removed.
    pub const fn without(self, output: Output) -> Outputs {
        Outputs(self.0 & !output.bit())
    }

    /// Whether `output` is asked for.
    pub const fn has(self, output: Output) -> bool {
        self.0 & output.bit() != 0
    }

    /// Whether any of `outputs` is asked for.
    pub fn any_of(self, outputs: &[Output]) -> bool {
        outputs.iter().any(|&o| self.has(o))
    }

    /// The requested outputs, in [`Output::ALL`]'s order.
    pub fn list(self) -> Vec<Output> {
        Output::ALL.into_iter().filter(|&o| self.has(o)).collect()
    }

    /// Stems ([`Output::stem`]) of the requested outputs among `of` (a technique's own).
    pub fn names(self, of: &[Output]) -> Vec<String> {
        of.iter()
            .filter(|&&o| self.has(o))
            .map(|o| o.stem().to_string())
            .collect()
    }
}

impl Default for Outputs {
    fn default() -> Self {
        Outputs::ALL
    }
}

impl std::fmt::Debug for Outputs {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_set().entries(self.list()).finish()
    }
}

impl Serialize for Outputs {
    /// `"all"` for [`Outputs::ALL`] (every output of whichever technique), else the list
    /// of stems.
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        if *self == Outputs::ALL {
            "all".serialize(s)
        } else {
            self.list().serialize(s)
        }
    }
}

impl<'de> Deserialize<'de> for Outputs {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::Error as _;
        match serde_json::Value::deserialize(d)? {
            serde_json::Value::String(all) if all == "all" => Ok(Outputs::ALL),
            serde_json::Value::Array(items) => {
                let mut set = Outputs::NONE;
                for item in items {
                    let name = item.as_str().ok_or_else(|| {
                        D::Error::custom(format!(
                            "outputs: expected output names ({}), found {item}",
                            stems(&Output::ALL)
                        ))
                    })?;
                    let o = Output::from_stem(name).ok_or_else(|| {
                        D::Error::custom(format!(
                            "outputs: unknown output `{name}`, expected one of {}",
                            stems(&Output::ALL)
                        ))
                    })?;
                    set = set.with(o);
                }
                Ok(set)
            }
            serde_json::Value::Object(flags) => {
                // the earlier form: one flag per output, a missing flag requested
                let mut set = Outputs::ALL;
                for (key, value) in flags {
                    let o = match key.as_str() {
                        "composite" => Output::Composite,
                        "direct" => Output::Direct,
                        "raw_caustics" => Output::RawCaustics,
                        "filtered_caustics" => Output::FilteredCaustics,
                        "atlas" => Output::CausticAtlas,
                        _ => {
                            return Err(D::Error::custom(format!(
                                "outputs: unknown flag `{key}`; outputs are now a list of \
                                 names: {}",
                                stems(&Output::ALL)
                            )))
                        }
                    };
                    let on = value.as_bool().ok_or_else(|| {
                        D::Error::custom(format!("outputs: `{key}` must be true or false"))
                    })?;
                    set = if on { set.with(o) } else { set.without(o) };
                }
                Ok(set)
            }
            other => Err(D::Error::custom(format!(
                "outputs: expected \"all\" or a list of output names ({}), found {other}",
                stems(&Output::ALL)
            ))),
        }
    }
}

/// One output of a technique, as [`crate::frame::technique::Technique::outputs`] lists it.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct OutputInfo {
    /// The output.
    pub output: Output,
    /// Its name ([`Output::stem`]), also the file-name stem.
    pub name: &'static str,
    /// What it holds ([`Output::description`]).
    pub description: &'static str,
    /// Whether the caller asked for it (only requested outputs can be read).
    pub requested: bool,
    /// Whether it is a camera-space image of the frame's size ([`Output::camera_space`]).
    pub camera_space: bool,
}

impl OutputInfo {
    /// `output`'s entry, requested or not.
    pub fn new(output: Output, requested: bool) -> OutputInfo {
        OutputInfo {
            output,
            name: output.stem(),
            description: output.description(),
            requested,
            camera_space: output.camera_space(),
        }
    }

    /// The entries of a technique's `own` outputs under the request `outputs`.
    pub fn list(own: &[Output], outputs: Outputs) -> Vec<OutputInfo> {
        own.iter()
            .map(|&o| OutputInfo::new(o, outputs.has(o)))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stems_name_each_output_once_and_parse_back() {
        for o in Output::ALL {
            assert_eq!(Output::from_stem(o.stem()), Some(o));
            assert_eq!(o.stem().parse::<Output>().ok(), Some(o));
            assert_eq!(serde_json::to_value(o).unwrap(), o.stem());
        }
        assert!("caustics".parse::<Output>().is_err());
    }

    #[test]
    fn the_json_form_is_a_list_and_the_earlier_flags_still_load() {
        let s = Outputs::of(&[Output::Composite, Output::FilteredCaustics]);
        let j = serde_json::to_value(s).unwrap();
        assert_eq!(j, serde_json::json!(["composite", "caustics_filtered"]));
        assert_eq!(serde_json::from_value::<Outputs>(j).unwrap(), s);
        let all = serde_json::to_value(Outputs::ALL).unwrap();
        assert_eq!(all, "all");
        assert_eq!(
            serde_json::from_value::<Outputs>(all).unwrap(),
            Outputs::ALL
        );
        let old: Outputs =
            serde_json::from_value(serde_json::json!({"direct": false, "atlas": false})).unwrap();
        assert_eq!(
            old,
            Outputs::ALL
                .without(Output::Direct)
                .without(Output::CausticAtlas)
        );
        let e = serde_json::from_value::<Outputs>(serde_json::json!(["caustics"])).unwrap_err();
        assert!(e.to_string().contains("caustics_filtered"), "{e}");
        let e = serde_json::from_value::<Outputs>(serde_json::json!({"indirect": true}));
        assert!(e.unwrap_err().to_string().contains("list of names"));
    }

    #[test]
    fn a_request_names_the_techniques_outputs_it_holds() {
        let own = [Output::Composite, Output::FilteredIndirect];
        assert!(!Outputs::CAUSTICS_ONLY.any_of(&own));
        assert!(Outputs::INDIRECT_ONLY.any_of(&own));
        assert_eq!(Outputs::ALL.names(&own), ["composite", "indirect"]);
    }
}
