// The emulated camera's GenICam description: Aravis's fake camera's, with Mono12 and PTP added.
#include "emulator_genicam.h"

#include "aravis_util.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

namespace multislit::emulator {

namespace {

// An unsigned 32-bit big-endian register of the device, as the fake camera's own.
std::string intReg(const char* name, std::uint32_t address, const char* access) {
  char text[400];
  std::snprintf(text, sizeof text,
                "\t<IntReg Name=\"%s\" NameSpace=\"Custom\">\n"
                "\t\t<Address>0x%x</Address>\n\t\t<Length>4</Length>\n"
                "\t\t<AccessMode>%s</AccessMode>\n\t\t<pPort>Device</pPort>\n"
                "\t\t<Sign>Unsigned</Sign>\n\t\t<Endianess>BigEndian</Endianess>\n"
                "\t</IntReg>\n",
                name, address, access);
  return text;
}

// SFNC's PtpEnable (a boolean) and PtpStatus (an enumeration), as PTP cameras have them.
std::string ptpFeatures() {
  return "\t<Boolean Name=\"PtpEnable\" NameSpace=\"Standard\">\n"
         "\t\t<pValue>PtpEnableRegister</pValue>\n"
         "\t\t<OnValue>1</OnValue>\n\t\t<OffValue>0</OffValue>\n"
         "\t</Boolean>\n" +
         intReg("PtpEnableRegister", kPtpEnableRegister, "RW") +
         "\t<Enumeration Name=\"PtpStatus\" NameSpace=\"Standard\">\n"
         "\t\t<EnumEntry Name=\"Disabled\" NameSpace=\"Standard\"><Value>0</Value></EnumEntry>\n"
         "\t\t<EnumEntry Name=\"Master\" NameSpace=\"Standard\"><Value>1</Value></EnumEntry>\n"
         "\t\t<EnumEntry Name=\"Slave\" NameSpace=\"Standard\"><Value>2</Value></EnumEntry>\n"
         "\t\t<pValue>PtpStatusRegister</pValue>\n"
         "\t</Enumeration>\n" +
         intReg("PtpStatusRegister", kPtpStatusRegister, "RO");
}

// Inserts `text` before the first `anchor` in `xml`; throws naming the anchor when it is absent.
void insertBefore(std::string& xml, const std::string& anchor, const std::string& text) {
  const std::size_t at = xml.find(anchor);
  if (at == std::string::npos)
    throw std::runtime_error("the Aravis fake camera's GenICam description has no '" + anchor +
                             "' to extend");
  xml.insert(at, text);
}

}  // namespace

std::string emulatorGenicam(const std::string& serial) {
  aravis::GPtr<ArvFakeCamera> fake(arv_fake_camera_new(serial.c_str()));
  std::size_t size = 0;
  const char* data = fake ? arv_fake_camera_get_genicam_xml(fake.get(), &size) : nullptr;
  if (data == nullptr)
    throw std::runtime_error("the Aravis fake camera has no GenICam description");
  std::string xml(data, size);
  // Mono12: 12 bits a pixel, sent in 16.
  insertBefore(xml, "<pValue>PixelFormatRegister</pValue>",
               "<EnumEntry Name=\"Mono12\" NameSpace=\"Standard\">\n\t\t\t<Value>" +
                   std::to_string(ARV_PIXEL_FORMAT_MONO_12) + "</Value>\n\t\t</EnumEntry>\n\t\t");
  insertBefore(xml, "</RegisterDescription>", ptpFeatures());
  return xml;
}

TemporaryFile::TemporaryFile(const std::string& text) {
  std::string name = (std::filesystem::temp_directory_path() / "multislit_genicam_XXXXXX").string();
  std::vector<char> buffer(name.begin(), name.end());
  buffer.push_back('\0');
  const int fd = ::mkstemp(buffer.data());
  if (fd < 0) throw std::runtime_error("cannot create a temporary file in " + name);
  path_ = buffer.data();
  const bool written = ::write(fd, text.data(), text.size()) == static_cast<ssize_t>(text.size());
  ::close(fd);
  if (!written) {
    std::remove(path_.c_str());
    throw std::runtime_error("cannot write the temporary file " + path_);
  }
}

TemporaryFile::~TemporaryFile() { std::remove(path_.c_str()); }

}  // namespace multislit::emulator
