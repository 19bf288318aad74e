// The exception of the VCI .NET API: every failing call throws it with the VCI error code
// (VCI_E_*, the HRESULT of the C API underneath) and a message that says what was wrong.
using System;

namespace Ixxat.Vci3
{
  [Serializable]
  public class VciException : Exception
  {
    readonly uint errorCode;

    public VciException(uint errorCode, string message) : base(message) { this.errorCode = errorCode; }
    public VciException(string message) : this(Native.E_UNEXPECTED, message) { }

    // The VCI error code (0xE001xxxx: VCI_E_*).
    public uint ErrorCode { get { return errorCode; } }
    // The same code as the HRESULT a COM caller would see.
    public int HResult32 { get { return unchecked((int)errorCode); } }

    internal static VciException Disposed(string what)
    {
      return new VciException(Native.E_INVHANDLE, what + " is disposed: the object was released with Dispose");
    }
  }
}
