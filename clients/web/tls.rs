//! The gateway's TLS: a certificate from files, or a self-signed one made at start.
//!
//! Browsers give motion sensors only to secure contexts (HTTPS, or plain `localhost`), so a
//! phone on the LAN needs HTTPS. A self-signed certificate is untrusted by any browser: the
//! user accepts it once, after comparing its SHA-256 fingerprint with the one printed.

use super::WebError;
use sha2::{Digest, Sha256};
use std::path::Path;
use std::sync::Arc;
use tokio_rustls::rustls::pki_types::pem::PemObject;
use tokio_rustls::rustls::pki_types::{CertificateDer, PrivateKeyDer};
use tokio_rustls::rustls::{self, ServerConfig};

/// A certificate chain and its key, ready for rustls.
pub struct Identity {
    /// Leaf first.
    pub chain: Vec<CertificateDer<'static>>,
    /// The leaf's private key.
    pub key: PrivateKeyDer<'static>,
    /// The leaf's PEM, when generated here (for tests and `--save-cert`).
    pub pem: Option<String>,
}

impl Identity {
    /// A fresh self-signed certificate for `names` (DNS names or IP addresses).
    pub fn self_signed(names: &[String]) -> Result<Identity, WebError> {
        let ck = rcgen::generate_simple_self_signed(names.to_vec())
            .map_err(|e| WebError::Tls(format!("cannot generate a certificate: {e}")))?;
        let key = PrivateKeyDer::try_from(ck.signing_key.serialize_der())
            .map_err(|e| WebError::Tls(format!("generated key: {e}")))?;
        Ok(Identity {
            chain: vec![ck.cert.der().clone()],
            key,
            pem: Some(ck.cert.pem()),
        })
    }

    /// A chain and key from PEM files (`--tls-cert`, `--tls-key`).
    pub fn from_files(cert: &Path, key: &Path) -> Result<Identity, WebError> {
        let chain: Vec<CertificateDer<'static>> = CertificateDer::pem_file_iter(cert)
            .and_then(|it| it.collect())
            .map_err(|e| WebError::Usage(format!("--tls-cert {}: {e}", cert.display())))?;
        if chain.is_empty() {
            return Err(WebError::Usage(format!(
                "--tls-cert {}: no certificate in the file",
                cert.display()
            )));
        }
        let key = PrivateKeyDer::from_pem_file(key)
            .map_err(|e| WebError::Usage(format!("--tls-key {}: {e}", key.display())))?;
        Ok(Identity {
            chain,
            key,
            pem: None,
        })
    }

    /// SHA-256 of the leaf certificate, as browsers show it: `AB:CD:…`.
    pub fn fingerprint(&self) -> String {
        fingerprint(&self.chain[0])
    }

    /// The rustls server configuration (HTTP/1.1 only, ring as the crypto provider).
    pub fn server_config(self) -> Result<Arc<ServerConfig>, WebError> {
        let provider = Arc::new(rustls::crypto::ring::default_provider());
        let mut cfg = ServerConfig::builder_with_provider(provider)
            .with_safe_default_protocol_versions()
            .map_err(|e| WebError::Tls(e.to_string()))?
            .with_no_client_auth()
            .with_single_cert(self.chain, self.key)
            .map_err(|e| WebError::Tls(format!("certificate and key do not fit: {e}")))?;
        cfg.alpn_protocols = vec![b"http/1.1".to_vec()];
        Ok(Arc::new(cfg))
    }
}

/// SHA-256 of a DER certificate, upper-case hex pairs joined by `:`.
pub fn fingerprint(der: &[u8]) -> String {
    let d = Sha256::digest(der);
    d.iter()
        .map(|b| format!("{b:02X}"))
        .collect::<Vec<_>>()
        .join(":")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_generated_certificate_has_a_fingerprint_and_loads_back() {
        let id = Identity::self_signed(&["localhost".into(), "127.0.0.1".into()]).unwrap();
        let fp = id.fingerprint();
        assert_eq!(fp.len(), 32 * 3 - 1);
        assert!(fp.split(':').all(|p| p.len() == 2));
        let dir = std::env::temp_dir().join(format!("tiltbox-web-tls-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let ck = rcgen::generate_simple_self_signed(vec!["localhost".to_string()]).unwrap();
        std::fs::write(dir.join("c.pem"), ck.cert.pem()).unwrap();
        std::fs::write(dir.join("k.pem"), ck.signing_key.serialize_pem()).unwrap();
        let back = Identity::from_files(&dir.join("c.pem"), &dir.join("k.pem")).unwrap();
        assert_eq!(back.fingerprint(), fingerprint(ck.cert.der()));
        assert!(back.server_config().is_ok());
        assert!(id.server_config().is_ok());
        let err = Identity::from_files(&dir.join("missing.pem"), &dir.join("k.pem"));
        assert!(matches!(err, Err(WebError::Usage(m)) if m.starts_with("--tls-cert")));
        let _ = std::fs::remove_dir_all(dir);
    }
}
