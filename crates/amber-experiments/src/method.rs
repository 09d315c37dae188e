//! The methods an experiment compares, and variants: named changes of a method's configuration
//! (every ablation is one), never forked code paths.

use std::fmt;
use std::str::FromStr;

use amber_graph::Aggregation;
use anyhow::Context;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use crate::report::merge_json;

/// A meshing method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(into = "String", try_from = "String")]
pub enum Method {
    /// AMBER with mean-projected labels.
    AmberMean,
    /// AMBER with max-projected labels.
    AmberMax,
    /// The U-Net baseline (spec §8) on a `resolution`^d pixel grid.
    Cnn { resolution: usize },
}

impl Method {
    /// The methods an experiment runs unless told otherwise, in table order.
    pub const DEFAULT: [Method; 2] = [Method::AmberMean, Method::AmberMax];

    /// The name used on the command line, in files and tables.
    pub fn name(self) -> String {
        match self {
            Method::AmberMean => "amber-mean".into(),
            Method::AmberMax => "amber-max".into(),
            Method::Cnn { resolution } => format!("cnn-{resolution}"),
        }
    }

    /// How the labels aggregate the expert sizes (the CNN's default is the mean).
    pub fn aggregation(self) -> Aggregation {
        match self {
            Method::AmberMax => Aggregation::Max,
            Method::AmberMean | Method::Cnn { .. } => Aggregation::Mean,
        }
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.name())
    }
}

impl From<Method> for String {
    fn from(method: Method) -> String {
        method.name()
    }
}

impl TryFrom<String> for Method {
    type Error = String;
    fn try_from(s: String) -> Result<Self, String> {
        s.parse()
    }
}

impl FromStr for Method {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        if let Some(r) = s.strip_prefix("cnn-") {
            return match r.parse::<usize>() {
                Ok(resolution) if resolution >= 16 && resolution.is_multiple_of(16) => Ok(Method::Cnn { resolution }),
                _ => Err(format!("`{s}`: the CNN resolution must be a multiple of 16 (cnn-32, cnn-64, ..., cnn-512)")),
            };
        }
        Method::DEFAULT.into_iter().find(|m| m.name() == s).ok_or_else(|| {
            format!("unknown method `{s}` (known: amber-mean, amber-max, cnn-<resolution> such as cnn-256)")
        })
    }
}

/// A named change of a method's training configuration: a JSON object merged into the
/// profile's config (see [`crate::merge_json`]). The default variant changes nothing.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Variant {
    pub name: String,
    pub overrides: serde_json::Value,
}

impl Variant {
    /// The method as configured by the profile.
    pub fn default_variant() -> Self {
        Self { name: "default".into(), overrides: serde_json::json!({}) }
    }

    /// A variant changing the given fields.
    pub fn new(name: &str, overrides: serde_json::Value) -> Self {
        Self { name: name.into(), overrides }
    }
}

/// One row of an experiment: a method in one variant.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MethodSpec {
    pub method: Method,
    pub variant: Variant,
}

impl MethodSpec {
    /// `method` as the profile configures it.
    pub fn plain(method: Method) -> Self {
        Self { method, variant: Variant::default_variant() }
    }

    /// The row label: the method name, plus the variant's unless it is the default.
    pub fn label(&self) -> String {
        match self.variant.name.as_str() {
            "default" => self.method.name(),
            variant => format!("{} ({variant})", self.method.name()),
        }
    }

    /// `base` (a run's config) with the user's `overrides` and then this variant's merged in.
    pub(crate) fn patched<T: Serialize + DeserializeOwned>(
        &self,
        base: &T,
        overrides: &serde_json::Value,
    ) -> anyhow::Result<T> {
        let mut value = serde_json::to_value(base)?;
        merge_json(&mut value, overrides);
        merge_json(&mut value, &self.variant.overrides);
        serde_json::from_value(value)
            .with_context(|| format!("the overrides of {} do not fit its configuration", self.label()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn method_names_round_trip_and_unknown_names_list_the_known() {
        for m in [Method::AmberMean, Method::AmberMax, Method::Cnn { resolution: 256 }] {
            assert_eq!(m.name().parse::<Method>().unwrap(), m);
            assert_eq!(serde_json::to_value(m).unwrap(), serde_json::json!(m.name()));
        }
        let err = "amber-median".parse::<Method>().unwrap_err();
        assert!(err.contains("amber-median") && err.contains("amber-max"), "{err}");
        assert!("cnn-100".parse::<Method>().unwrap_err().contains("multiple of 16"));
    }
}
