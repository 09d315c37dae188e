//! The methods an experiment compares, and variants: named changes of a method's configuration
//! (every ablation is one), never forked code paths.

use std::fmt;
use std::str::FromStr;

use amber_graph::Aggregation;
use serde::{Deserialize, Serialize};

/// A meshing method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// AMBER with mean-projected labels.
    AmberMean,
    /// AMBER with max-projected labels.
    AmberMax,
}

impl Method {
    /// Every method, in table order.
    pub const ALL: [Method; 2] = [Method::AmberMean, Method::AmberMax];

    /// The name used on the command line, in files and tables.
    pub fn name(self) -> &'static str {
        match self {
            Method::AmberMean => "amber-mean",
            Method::AmberMax => "amber-max",
        }
    }

    /// How AMBER's labels aggregate the expert sizes.
    pub fn aggregation(self) -> Aggregation {
        match self {
            Method::AmberMean => Aggregation::Mean,
            Method::AmberMax => Aggregation::Max,
        }
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Method {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Method::ALL.into_iter().find(|m| m.name() == s).ok_or_else(|| {
            let known: Vec<&str> = Method::ALL.iter().map(|m| m.name()).collect();
            format!("unknown method `{s}` (known: {})", known.join(", "))
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
            "default" => self.method.name().to_string(),
            variant => format!("{} ({variant})", self.method.name()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn method_names_round_trip_and_unknown_names_list_the_known() {
        for m in Method::ALL {
            assert_eq!(m.name().parse::<Method>().unwrap(), m);
            assert_eq!(serde_json::to_value(m).unwrap(), serde_json::json!(m.name()));
        }
        let err = "amber-median".parse::<Method>().unwrap_err();
        assert!(err.contains("amber-median") && err.contains("amber-max"), "{err}");
    }
}
