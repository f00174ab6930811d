//! Memory budgets for what grows with n²: the dense Jacobians and LU factors of the implicit
//! methods, refused with a typed error before they are allocated instead of aborting the
//! process when the allocator fails.
//!
//! ```text
//! available = min( MemAvailable                        (/proc/meminfo)
//!                  cgroup memory.max − memory.current  (/sys/fs/cgroup, cgroup v2)
//!                  soft RLIMIT_AS − VmSize             (/proc/self/limits, /proc/self/status) )
//! budget    = max_memory when given, else SHARE · available      (SHARE = 1/2)
//! need      = 8 · k · n² bytes for k dense n × n f64 matrices  (dense_matrices(method))
//! need > budget  →  MemoryError { what, needed, budget, basis }
//! need ≤ SMALL and no max_memory  →  admitted without reading the files (SMALL = 1 MiB)
//! ```
//!
//! The share leaves the other half of what is free to everything that grows linearly (the
//! state, stages, the output record) and to the rest of the process. Where no figure is known
//! (not Linux, /proc unreadable) and no `max_memory` is given, nothing is refused here; the
//! allocations that this crate makes itself are still fallible ([`try_zeros`]), but diffsol's
//! own (nalgebra) matrices are not.
//!
//! k per method (measured: the growth of VmPeak for y' = −y at n = 3000, python/tests/
//! test_edges.py's procedure): diffsol's BDF, TR-BDF2 and ESDIRK3(4) 4.0 (our Jacobian
//! scratch, diffsol's ∂f/∂y, its identity mass matrix stored dense, the LU), Rodas5P 2.93
//! (∂f/∂y, the LU and faer's scratch of the factorisation; counted as 3), the explicit methods
//! and RK4 0.
//!
//! The sparse path of diffsol's methods and Rodas5P (crate::linear_algebra) stores no n × n
//! matrix: its
//! need is counted per entry of the pattern of ∂f/∂y (nnz) and of the Newton matrix
//! (nnz + n, with the diagonal), [`sparse_bytes`]:
//!
//! ```text
//! need = SPARSE_BYTES_PER_ENTRY · (nnz + n)      (SPARSE_BYTES_PER_ENTRY = 80)
//!        the pattern and its colouring (8), ∂f/∂y in compressed columns (16), the Newton
//!        matrix (16), its LU factors with up to as many entries again of fill (32), faer's
//!        scratch and diffsol's vectors (8)
//! ```
//! Fill beyond that (a pattern whose LU fills in) is not foreseen by the estimate; the
//! patterns of mechanisms are block diagonal, whose LU has no fill.
//!
//! The `kkt` path (crate::kkt) stores K (its triplets and values, n_K entries), R = ∂ρ/∂y
//! (n_R entries, twice: the last linearisation and the factored one), the augmented matrix
//! (2 n_q + n_R + n_K entries) and the two sparse LUs (K's and the augmented matrix's), each
//! counted with as many entries again of fill, [`kkt_bytes`]:
//!
//! ```text
//! need = SPARSE_BYTES_PER_ENTRY · (2 n_K + 2 n_R + 2 n_q + n)
//! ```
//! A chain's K and R are banded (COLAMD keeps their LUs' fill within the band): the estimate
//! and the measured peak are compared in BENCHMARKS.md ("The sparse Newton of one cluster").
//!
//! Source: issue 23 ("No process death on memory"); proc(5) for the files read.

use std::fmt;

use faer::Mat;

use crate::method::Method;

/// The share of the available memory that the n² allocations of one integration may use
/// when no `max_memory` is given.
pub const SHARE: f64 = 0.5;

/// Needs at or under this many bytes are admitted without reading the system's figures when
/// no `max_memory` is given. Reading them (five files of /proc and /sys) took 0.16 ms per
/// integration, 9 % of the lubricated press's bdf run under the minimal formulation
/// (BENCHMARKS.md, "The press targets through `lash run`"), for matrices of a few hundred
/// bytes; 1 MiB is bdf's four matrices up to n = 181, and a process with less than twice
/// that free would not have got this far. A `max_memory` is always compared.
pub const SMALL: u64 = 1 << 20;

/// Bytes of one f64.
const F64: u64 = 8;

/// An allocation refused because it would exceed the memory budget, or that the allocator
/// refused.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MemoryError {
    /// What needed the memory ("bdf's dense Jacobian and LU: 4 matrices of 18000 × 18000").
    pub what: String,
    /// Bytes needed.
    pub needed: u64,
    /// The budget in bytes (0 when the allocator itself failed and no budget was known).
    pub budget: u64,
    /// Where the budget comes from ("max_memory", "half of MemAvailable", "the allocator").
    pub basis: String,
}

impl fmt::Display for MemoryError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.budget == 0 {
            write!(
                f,
                "not enough memory: {} needs {} and {} refused it",
                self.what,
                human(self.needed),
                self.basis
            )
        } else {
            write!(
                f,
                "not enough memory: {} needs {}, over the budget of {} ({})",
                self.what,
                human(self.needed),
                human(self.budget),
                self.basis
            )
        }
    }
}

impl std::error::Error for MemoryError {}

/// Bytes as "2.59 GB (2592000000 bytes)": decimal units, and the exact count.
pub fn human(bytes: u64) -> String {
    let b = bytes as f64;
    let (v, unit) = if b >= 1e9 {
        (b / 1e9, "GB")
    } else if b >= 1e6 {
        (b / 1e6, "MB")
    } else if b >= 1e3 {
        (b / 1e3, "kB")
    } else {
        return format!("{bytes} bytes");
    };
    format!("{v:.3} {unit} ({bytes} bytes)")
}

/// Dense n × n f64 matrices a method allocates for a system of dimension n (module doc: k).
pub fn dense_matrices(method: Method) -> u64 {
    match method {
        Method::Bdf | Method::Trbdf2 | Method::Esdirk34 => 4,
        Method::Rodas5p => 3,
        Method::Rk4 | Method::Bs32 | Method::Dopri54 | Method::Tsit54 | Method::Dop853 => 0,
    }
}

/// Bytes of `k` dense n × n f64 matrices (saturating: a size that does not fit in u64 is
/// u64::MAX, which no budget admits).
pub fn dense_bytes(n: usize, k: u64) -> u64 {
    (n as u64)
        .checked_mul(n as u64)
        .and_then(|v| v.checked_mul(F64))
        .and_then(|v| v.checked_mul(k))
        .unwrap_or(u64::MAX)
}

/// The memory the process can still use, in bytes, and what limits it; None when no figure is
/// known (module doc).
pub fn available() -> Option<(u64, &'static str)> {
    let read = |p: &str| std::fs::read_to_string(p).ok();
    let mut best: Option<(u64, &'static str)> = None;
    let mut take = |v: Option<u64>, what: &'static str| {
        if let Some(v) = v {
            if best.is_none_or(|(b, _)| v < b) {
                best = Some((v, what));
            }
        }
    };
    take(
        read("/proc/meminfo").and_then(|s| meminfo_available(&s)),
        "MemAvailable",
    );
    take(cgroup_headroom(), "the cgroup's memory.max");
    let limit = read("/proc/self/limits").and_then(|s| address_space_limit(&s));
    let size = read("/proc/self/status").and_then(|s| vm_size(&s));
    if let (Some(limit), Some(size)) = (limit, size) {
        take(Some(limit.saturating_sub(size)), "RLIMIT_AS");
    }
    best
}

/// The budget of the n² allocations (module doc) and where it comes from; None when nothing
/// is known and no `max_memory` was given.
pub fn budget(max_memory: Option<u64>) -> Option<(u64, String)> {
    if let Some(m) = max_memory {
        return Some((m, "max_memory".into()));
    }
    available().map(|(a, what)| {
        (
            (SHARE * a as f64) as u64,
            format!("half of the {} available by {what}", human(a)),
        )
    })
}

/// Checks that `needed` bytes fit the budget (`what` names them in the error).
pub fn check(
    needed: u64,
    what: impl FnOnce() -> String,
    max_memory: Option<u64>,
) -> Result<(), MemoryError> {
    if max_memory.is_none() && needed <= SMALL {
        return Ok(());
    }
    match budget(max_memory) {
        Some((b, basis)) if needed > b => Err(MemoryError {
            what: what(),
            needed,
            budget: b,
            basis,
        }),
        _ => Ok(()),
    }
}

/// Checks the dense matrices of `method` for a system of dimension `n` against the budget.
pub fn check_method(method: Method, n: usize, max_memory: Option<u64>) -> Result<(), MemoryError> {
    let k = dense_matrices(method);
    if k == 0 {
        return Ok(());
    }
    check(
        dense_bytes(n, k),
        || format!("{method}'s dense Jacobian and LU ({k} matrices of {n} × {n} f64)"),
        max_memory,
    )
}

/// Bytes per entry of the sparse path's estimate (module doc).
pub const SPARSE_BYTES_PER_ENTRY: u64 = 80;

/// The sparse path's need for a system of dimension `n` whose ∂f/∂y pattern has `nnz`
/// entries (module doc), saturating.
pub fn sparse_bytes(n: usize, nnz: usize) -> u64 {
    (nnz as u64)
        .saturating_add(n as u64)
        .saturating_mul(SPARSE_BYTES_PER_ENTRY)
}

/// Checks the sparse matrices of `method` (one of diffsol's) for a system of dimension `n`
/// with `nnz` entries in its Jacobian's pattern against the budget.
pub fn check_sparse(
    method: Method,
    n: usize,
    nnz: usize,
    max_memory: Option<u64>,
) -> Result<(), MemoryError> {
    check(
        sparse_bytes(n, nnz),
        || format!("{method}'s sparse Jacobian and LU ({nnz} entries, n = {n})"),
        max_memory,
    )
}

/// The `kkt` path's need for a system of `shape` (module doc), saturating.
pub fn kkt_bytes(shape: &crate::system::KktShape) -> u64 {
    let nnz_r: usize = shape.residual_pattern.iter().map(Vec::len).sum();
    // K_ε's −εI block, when the path regularises K (crate::kkt).
    let k_entries = shape.k_entries + shape.regularisation.map_or(0, |_| shape.m);
    let entries = (k_entries as u64)
        .saturating_mul(2)
        .saturating_add((nnz_r as u64).saturating_mul(2))
        .saturating_add(4 * shape.nq as u64);
    entries.saturating_mul(SPARSE_BYTES_PER_ENTRY)
}

/// Checks the `kkt` path's matrices of `method` for a system of `shape` against the budget.
pub fn check_kkt(
    method: Method,
    shape: &crate::system::KktShape,
    max_memory: Option<u64>,
) -> Result<(), MemoryError> {
    check(
        kkt_bytes(shape),
        || {
            format!(
                "{method}'s KKT Newton matrices (n_q = {}, m = {})",
                shape.nq, shape.m
            )
        },
        max_memory,
    )
}

/// An r × c matrix of zeros, or a [`MemoryError`] when the allocator refuses it (instead of
/// faer's panic).
pub fn try_zeros(r: usize, c: usize) -> Result<Mat<f64>, MemoryError> {
    let mut m = Mat::<f64>::new();
    m.try_reserve(r, c).map_err(|_| MemoryError {
        what: format!("a {r} × {c} f64 matrix"),
        needed: (r as u64).saturating_mul(c as u64).saturating_mul(F64),
        budget: 0,
        basis: "the allocator".into(),
    })?;
    m.resize_with(r, c, |_, _| 0.0);
    Ok(m)
}

/// `MemAvailable` of /proc/meminfo, in bytes.
fn meminfo_available(s: &str) -> Option<u64> {
    kib_field(s, "MemAvailable:")
}

/// `VmSize` of /proc/self/status, in bytes.
fn vm_size(s: &str) -> Option<u64> {
    kib_field(s, "VmSize:")
}

/// A "Key:   1234 kB" line's value in bytes.
fn kib_field(s: &str, key: &str) -> Option<u64> {
    let line = s.lines().find(|l| l.starts_with(key))?;
    let kib: u64 = line[key.len()..].split_whitespace().next()?.parse().ok()?;
    kib.checked_mul(1024)
}

/// The soft limit of "Max address space" in /proc/self/limits, in bytes (None: unlimited).
fn address_space_limit(s: &str) -> Option<u64> {
    let line = s.lines().find(|l| l.starts_with("Max address space"))?;
    let soft = line["Max address space".len()..]
        .split_whitespace()
        .next()?;
    soft.parse().ok()
}

/// memory.max − memory.current of this process's cgroup (v2), in bytes; None when there is
/// no limit ("max") or no cgroup v2.
fn cgroup_headroom() -> Option<u64> {
    let cg = std::fs::read_to_string("/proc/self/cgroup").ok()?;
    let path = cg.lines().find_map(|l| l.strip_prefix("0::"))?;
    let dir = format!("/sys/fs/cgroup{}", path.trim_end());
    let max = std::fs::read_to_string(format!("{dir}/memory.max")).ok()?;
    let max: u64 = max.trim().parse().ok()?;
    let cur = std::fs::read_to_string(format!("{dir}/memory.current")).ok()?;
    let cur: u64 = cur.trim().parse().ok()?;
    Some(max.saturating_sub(cur))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn proc_files_are_read_as_proc5_writes_them() {
        let meminfo = "MemTotal:       24576000 kB\nMemFree:        1000 kB\n\
                       MemAvailable:   22000000 kB\nBuffers:        10 kB\n";
        assert_eq!(meminfo_available(meminfo), Some(22_000_000 * 1024));
        let status = "Name:\tpython3\nVmPeak:\t  500000 kB\nVmSize:\t  412345 kB\n";
        assert_eq!(vm_size(status), Some(412_345 * 1024));
        let limits = "Limit                     Soft Limit           Hard Limit           Units     \n\
                      Max cpu time              unlimited            unlimited            seconds   \n\
                      Max address space         6442450944           unlimited            bytes     \n";
        assert_eq!(address_space_limit(limits), Some(6 << 30));
        let unlimited = limits.replace("6442450944 ", "unlimited  ");
        assert_eq!(address_space_limit(&unlimited), None);
    }

    #[test]
    fn dense_sizes_are_8_k_n_squared_and_saturate() {
        // The issue's finding: one 18000 × 18000 Jacobian is 2 592 000 000 bytes.
        assert_eq!(dense_bytes(18_000, 1), 2_592_000_000);
        assert_eq!(dense_bytes(18_000, 4), 4 * 2_592_000_000);
        assert_eq!(dense_bytes(usize::MAX, 1), u64::MAX);
        assert_eq!(dense_matrices(Method::Dopri54), 0);
        assert!(check_method(Method::Dopri54, usize::MAX, Some(1)).is_ok());
    }

    #[test]
    fn max_memory_is_the_budget() {
        // BDF at n = 100: 4 · 100² · 8 = 320 000 bytes.
        assert!(check_method(Method::Bdf, 100, Some(320_000)).is_ok());
        let e = check_method(Method::Bdf, 100, Some(319_999)).unwrap_err();
        assert_eq!((e.needed, e.budget), (320_000, 319_999));
        assert_eq!(e.basis, "max_memory");
        let msg = e.to_string();
        assert!(msg.contains("bdf") && msg.contains("320.000 kB"), "{msg}");
    }

    #[test]
    fn the_sparse_need_grows_with_the_entries_not_with_n_squared() {
        // 3 000 free bodies: n = 18 000, 6 × 6 blocks, nnz = 36 n = 648 000:
        // 80 · (648 000 + 18 000) bytes = 53.28 MB, against 4 · 8 · 18 000² = 10.4 GB dense.
        assert_eq!(sparse_bytes(18_000, 648_000), 53_280_000);
        assert!(check_sparse(Method::Bdf, 18_000, 648_000, Some(53_280_000)).is_ok());
        let e = check_sparse(Method::Bdf, 18_000, 648_000, Some(53_279_999)).unwrap_err();
        assert_eq!((e.needed, e.budget), (53_280_000, 53_279_999));
        assert!(e.to_string().contains("648000 entries"), "{e}");
        assert!(check_method(Method::Bdf, 18_000, Some(1 << 30)).is_err());
        assert_eq!(sparse_bytes(usize::MAX, usize::MAX), u64::MAX);
    }

    #[test]
    fn a_small_need_is_admitted_unread_but_a_max_memory_still_binds() {
        // bdf at n = 181: 4 · 181² · 8 = 1 048 352 bytes ≤ SMALL, admitted without a budget;
        // n = 182 (1 059 968 bytes) is over SMALL and goes through the figures again.
        assert!(dense_bytes(181, 4) <= SMALL && dense_bytes(182, 4) > SMALL);
        assert!(check_method(Method::Bdf, 181, None).is_ok());
        // A max_memory is compared whatever the size: 4 · 4² · 8 = 512 bytes.
        let e = check_method(Method::Bdf, 4, Some(511)).unwrap_err();
        assert_eq!((e.needed, e.budget), (512, 511));
        assert!(check_method(Method::Bdf, 4, Some(512)).is_ok());
    }

    #[test]
    fn an_impossible_matrix_is_an_error_not_a_panic() {
        let e = try_zeros(usize::MAX / 8, 2).unwrap_err();
        assert_eq!(e.basis, "the allocator");
        let m = try_zeros(3, 2).unwrap();
        assert_eq!((m.nrows(), m.ncols(), m[(2, 1)]), (3, 2, 0.0));
    }
}
