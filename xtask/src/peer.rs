//! Peer benchmarks: a Python script times the same work in another library, in the same
//! invocation as ours, on the very input ours worked on.
//!
//! A bench writes its input (a mesh, points, a sizing field) into a [`PeerDir`] as `.npy` arrays
//! and `input.json`, runs the script with [`Peer::run_script`] (`python xtask/peers/SCRIPT DIR`)
//! and reads the `result.json` the script leaves there. The scripts live in `xtask/peers/`
//! (`amber_peer.py` is what they share); the PyTorch peers of `../shared/peers/` go through
//! [`Peer::run`] with their own arguments. Either way the script gets the bench's thread count in
//! every variable the numeric libraries read, with passive OpenMP waiting (a shared machine's
//! other processes would otherwise slow spinning threads many times over).

use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{Context, bail};
use serde_json::Value;

/// Where our peer scripts live, from the workspace root.
pub const SCRIPTS: &str = "xtask/peers";

/// A Python interpreter with the peer libraries, and the threads it may use.
pub struct Peer<'a> {
    pub python: &'a Path,
    pub threads: usize,
}

impl Peer<'_> {
    /// Runs our script `xtask/peers/<script>` on the inputs in `dir`; returns its `result.json`.
    pub fn run_script(&self, script: &str, dir: &PeerDir) -> anyhow::Result<Value> {
        self.run(&Path::new(SCRIPTS).join(script), &[dir.path()], &[], dir, "result.json")
    }

    /// Runs `script` with `args` and extra environment `env`, `PEERS_RESULTS` set to `dir`, and
    /// returns the JSON file `result` the script wrote into `dir`.
    pub fn run(
        &self,
        script: &Path,
        args: &[impl AsRef<OsStr>],
        env: &[(&str, String)],
        dir: &PeerDir,
        result: &str,
    ) -> anyhow::Result<Value> {
        let threads = self.threads.to_string();
        let mut command = Command::new(self.python);
        command.arg(script).args(args).env("PEERS_RESULTS", dir.path()).env("PEERS_THREADS", &threads);
        for var in ["OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS"] {
            command.env(var, &threads);
        }
        command.env("OMP_WAIT_POLICY", "PASSIVE").env("PEERS_OMP_WAIT_POLICY", "PASSIVE");
        // No __pycache__ beside the scripts in the checkout.
        command.env("PYTHONDONTWRITEBYTECODE", "1");
        command.envs(env.iter().map(|(k, v)| (k, v)));
        let status =
            command.status().with_context(|| format!("running {} {}", self.python.display(), script.display()))?;
        if !status.success() {
            bail!("the peer benchmark {} failed: {status}", script.display());
        }
        dir.read_json(result)
    }
}

/// A scratch directory for one peer run (inputs from us, results from the script), removed
/// when dropped.
pub struct PeerDir {
    path: PathBuf,
}

impl PeerDir {
    /// An empty directory `amber-peer-<name>-<pid>` in the system's temporary directory.
    pub fn new(name: &str) -> anyhow::Result<Self> {
        let path = std::env::temp_dir().join(format!("amber-peer-{name}-{}", std::process::id()));
        if path.exists() {
            std::fs::remove_dir_all(&path).with_context(|| format!("clearing {}", path.display()))?;
        }
        std::fs::create_dir_all(&path).with_context(|| format!("creating {}", path.display()))?;
        Ok(Self { path })
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Writes `input.json`: the settings of the case.
    pub fn write_input(&self, input: &Value) -> anyhow::Result<()> {
        let path = self.path.join("input.json");
        std::fs::write(&path, serde_json::to_vec_pretty(input)?).with_context(|| format!("writing {}", path.display()))
    }

    /// Writes `<name>.npy`: `data` in row-major order with `shape`.
    pub fn write_npy<T: NpyElement>(&self, name: &str, shape: &[usize], data: &[T]) -> anyhow::Result<()> {
        let path = self.path.join(format!("{name}.npy"));
        std::fs::write(&path, npy::encode(shape, data)?).with_context(|| format!("writing {}", path.display()))
    }

    /// Reads `<name>.npy` (written by the script): its shape and data.
    pub fn read_npy<T: NpyElement>(&self, name: &str) -> anyhow::Result<(Vec<usize>, Vec<T>)> {
        let path = self.path.join(format!("{name}.npy"));
        let bytes = std::fs::read(&path).with_context(|| format!("reading {}", path.display()))?;
        npy::decode(&bytes).with_context(|| format!("{}", path.display()))
    }

    fn read_json(&self, name: &str) -> anyhow::Result<Value> {
        let path = self.path.join(name);
        let text = std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
        serde_json::from_str(&text).with_context(|| format!("parsing {}", path.display()))
    }
}

impl Drop for PeerDir {
    fn drop(&mut self) {
        std::fs::remove_dir_all(&self.path).ok();
    }
}

/// An element type of `.npy` arrays we exchange: little-endian `f64` and `u32`.
pub trait NpyElement: Copy {
    /// numpy's type string.
    const DESCR: &'static str;
    const SIZE: usize;
    fn put(self, out: &mut Vec<u8>);
    fn get(bytes: &[u8]) -> Self;
}

impl NpyElement for f64 {
    const DESCR: &'static str = "<f8";
    const SIZE: usize = 8;
    fn put(self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_le_bytes());
    }
    fn get(bytes: &[u8]) -> Self {
        f64::from_le_bytes(bytes.try_into().expect("8 bytes"))
    }
}

impl NpyElement for u32 {
    const DESCR: &'static str = "<u4";
    const SIZE: usize = 4;
    fn put(self, out: &mut Vec<u8>) {
        out.extend_from_slice(&self.to_le_bytes());
    }
    fn get(bytes: &[u8]) -> Self {
        u32::from_le_bytes(bytes.try_into().expect("4 bytes"))
    }
}

/// numpy's `.npy` format, version 1.0, C order: the magic `\x93NUMPY`, the version, the header
/// length (u16), a Python dict literal padded with spaces to a multiple of 64 bytes and ended by
/// a newline, then the raw data. What `numpy.save` writes for these types, byte for byte.
mod npy {
    use super::NpyElement;
    use anyhow::{Context, bail, ensure};

    const MAGIC: &[u8] = b"\x93NUMPY";

    pub fn encode<T: NpyElement>(shape: &[usize], data: &[T]) -> anyhow::Result<Vec<u8>> {
        ensure!(shape.iter().product::<usize>() == data.len(), "shape {shape:?} does not hold {} elements", data.len());
        let dims: Vec<String> = shape.iter().map(usize::to_string).collect();
        let shape = if dims.len() == 1 { format!("({},)", dims[0]) } else { format!("({})", dims.join(", ")) };
        let mut header = format!("{{'descr': '{}', 'fortran_order': False, 'shape': {shape}, }}", T::DESCR);
        // Magic, version and length take 10 bytes; the newline ends the padded header.
        let padded = (10 + header.len() + 1).next_multiple_of(64) - 10;
        header.extend(std::iter::repeat_n(' ', padded - header.len() - 1));
        header.push('\n');
        let mut out = Vec::with_capacity(10 + header.len() + data.len() * T::SIZE);
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&[1, 0]);
        out.extend_from_slice(&u16::try_from(header.len()).context("npy header too long")?.to_le_bytes());
        out.extend_from_slice(header.as_bytes());
        for &x in data {
            x.put(&mut out);
        }
        Ok(out)
    }

    pub fn decode<T: NpyElement>(bytes: &[u8]) -> anyhow::Result<(Vec<usize>, Vec<T>)> {
        ensure!(bytes.len() >= 10 && bytes.starts_with(MAGIC), "not an .npy file");
        let (header_len, start) = match bytes[6] {
            1 => (usize::from(u16::from_le_bytes([bytes[8], bytes[9]])), 10),
            2 | 3 if bytes.len() >= 12 => (u32::from_le_bytes(bytes[8..12].try_into()?) as usize, 12),
            v => bail!("unsupported .npy version {v}"),
        };
        let header = bytes.get(start..start + header_len).context("truncated .npy header")?;
        let header = std::str::from_utf8(header).context("non-UTF-8 .npy header")?;
        let field = |key: &str| -> anyhow::Result<&str> {
            let rest = header.split_once(&format!("'{key}':")).with_context(|| format!("no '{key}' in {header}"))?.1;
            Ok(rest.trim_start())
        };
        let descr = field("descr")?;
        ensure!(
            descr.starts_with(&format!("'{}'", T::DESCR)),
            "element type {} expected, the file has {}",
            T::DESCR,
            descr.split(',').next().unwrap_or(descr)
        );
        ensure!(field("fortran_order")?.starts_with("False"), "Fortran-order arrays are not read");
        let shape = field("shape")?;
        let shape = shape.strip_prefix('(').and_then(|s| s.split_once(')')).context("malformed shape")?.0;
        let shape = shape
            .split(',')
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .map(|s| s.parse::<usize>().with_context(|| format!("malformed shape entry `{s}`")))
            .collect::<anyhow::Result<Vec<_>>>()?;
        let data = &bytes[start + header_len..];
        let count: usize = shape.iter().product();
        ensure!(
            data.len() == count * T::SIZE,
            "shape {shape:?} needs {} bytes of data, the file has {}",
            count * T::SIZE,
            data.len()
        );
        Ok((shape, data.chunks_exact(T::SIZE).map(T::get).collect()))
    }

    #[cfg(test)]
    mod tests {
        use super::*;

        /// What `numpy.save(f, numpy.array([[1.0, 2.0], [3.5, -4.0]]))` writes (numpy 2.4).
        #[test]
        fn matches_numpy_byte_for_byte() {
            let mut expected =
                b"\x93NUMPY\x01\x00v\x00{'descr': '<f8', 'fortran_order': False, 'shape': (2, 2), }".to_vec();
            expected.resize(127, b' ');
            expected.push(b'\n');
            for x in [1.0f64, 2.0, 3.5, -4.0] {
                expected.extend_from_slice(&x.to_le_bytes());
            }
            assert_eq!(encode(&[2, 2], &[1.0, 2.0, 3.5, -4.0]).unwrap(), expected);
            // One dimension is written as a one-element tuple.
            let bytes = encode(&[3], &[7u32, 8, 9]).unwrap();
            assert!(
                bytes.starts_with(b"\x93NUMPY\x01\x00v\x00{'descr': '<u4', 'fortran_order': False, 'shape': (3,), }")
            );
            assert_eq!(bytes.len(), 128 + 12);
        }

        #[test]
        fn round_trips() {
            let data: Vec<f64> = (0..600).map(|i| f64::from(i) * 0.1 - 7.0).collect();
            for shape in [vec![600], vec![200, 3], vec![2, 3, 100]] {
                let bytes = encode(&shape, &data).unwrap();
                assert_eq!((10 + usize::from(u16::from_le_bytes([bytes[8], bytes[9]]))) % 64, 0);
                assert_eq!(decode::<f64>(&bytes).unwrap(), (shape, data.clone()));
            }
            let cells = vec![0u32, 1, 2, u32::MAX];
            assert_eq!(decode::<u32>(&encode(&[2, 2], &cells).unwrap()).unwrap(), (vec![2, 2], cells));
            assert_eq!(decode::<u32>(&encode::<u32>(&[0, 3], &[]).unwrap()).unwrap(), (vec![0, 3], vec![]));
        }

        #[test]
        fn rejects_what_it_cannot_read() {
            let bytes = encode(&[2], &[1.0, 2.0]).unwrap();
            assert!(decode::<u32>(&bytes).unwrap_err().to_string().contains("<u4 expected"));
            assert!(decode::<f64>(&bytes[..bytes.len() - 1]).is_err());
            assert!(decode::<f64>(b"not numpy").is_err());
            assert!(encode(&[3], &[1.0]).is_err());
        }
    }
}
