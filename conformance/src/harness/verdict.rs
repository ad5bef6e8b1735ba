//! The outcome of a comparison ([`Verdict`]: measured numbers and failed checks) and of a
//! test ([`Report`]: every verdict over backends and cases, failing once at the end with all
//! of them).

use super::candidates::loud;
use std::fmt;

/// The outcome of one comparison: measured numbers (notes) and failed checks.
#[derive(Clone, Debug, Default)]
pub struct Verdict {
    pub what: String,
    pub notes: Vec<String>,
    pub failures: Vec<String>,
}

impl Verdict {
    pub fn new(what: impl Into<String>) -> Verdict {
        Verdict {
            what: what.into(),
            ..Default::default()
        }
    }

    pub fn note(&mut self, s: impl Into<String>) {
        self.notes.push(s.into());
    }

    /// Records a failure unless `ok`; returns `ok`.
    pub fn check(&mut self, ok: bool, msg: impl FnOnce() -> String) -> bool {
        if !ok {
            self.failures.push(msg());
        }
        ok
    }

    pub fn fail(&mut self, msg: impl Into<String>) {
        self.failures.push(msg.into());
    }

    /// Adds another verdict's notes and failures, prefixed with its name.
    pub fn absorb(&mut self, other: Verdict) {
        for n in other.notes {
            self.notes.push(format!("{}: {n}", other.what));
        }
        for f in other.failures {
            self.failures.push(format!("{}: {f}", other.what));
        }
    }

    pub fn passed(&self) -> bool {
        self.failures.is_empty()
    }
}

impl fmt::Display for Verdict {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let tag = if self.passed() { "ok  " } else { "FAIL" };
        writeln!(f, "[{tag}] {}", self.what)?;
        for n in &self.notes {
            writeln!(f, "         {n}")?;
        }
        for x in &self.failures {
            writeln!(f, "   !!!   {x}")?;
        }
        Ok(())
    }
}

/// Collects the verdicts of one test over backends and cases; [`Report::finish`] panics
/// with every failure at once, so a backend author sees all departures in one run.
pub struct Report {
    test: String,
    verdicts: Vec<Verdict>,
}

impl Report {
    pub fn new(test: &str) -> Report {
        Report {
            test: test.into(),
            verdicts: Vec::new(),
        }
    }

    /// Adds `v` as "`backend` / `case`: what".
    pub fn add(&mut self, backend: &str, case: &str, mut v: Verdict) {
        v.what = format!("{backend} / {case}: {}", v.what);
        eprint!("{v}");
        self.verdicts.push(v);
    }

    /// Adds an error that prevented a comparison.
    pub fn error(&mut self, backend: &str, case: &str, e: String) {
        let mut v = Verdict::new("could not run");
        v.fail(e);
        self.add(backend, case, v);
    }

    /// Names ("backend / case: what") of the verdicts that passed.
    pub fn passed_cases(&self) -> Vec<String> {
        self.verdicts
            .iter()
            .filter(|v| v.passed())
            .map(|v| v.what.clone())
            .collect()
    }

    pub fn finish(self) {
        let failed: Vec<&Verdict> = self.verdicts.iter().filter(|v| !v.passed()).collect();
        let msg = format!(
            "{}: {} comparisons, {} failed",
            self.test,
            self.verdicts.len(),
            failed.len()
        );
        loud(&msg);
        if !failed.is_empty() {
            let all: String = failed.iter().map(|v| v.to_string()).collect();
            panic!("{msg}\n{all}");
        }
    }
}
